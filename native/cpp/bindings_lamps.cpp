// pybind11 bindings of the lamp kernels (lamps.h), registered into dacrt._core by
// register_lamps(). Shapes, dtypes, record codes and indices are checked here (the Python
// wrappers in dacrt/lamps.py convert arguments); outputs are written in place, so they must be
// exactly float32, C-contiguous and writeable (a converted copy would silently lose the
// result). The GIL is released while a kernel runs.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "bindargs.h"
#include "bounce.h"
#include "choiceruns.h"
#include "orennayar.h"
#include "shading.h"
#include "environment.h"
#include "envbuild.h"
#include "envlanes.h"
#include "equirect.h"
#include "ies.h"
#include "lamps.h"
#include "nextevent.h"

namespace py = pybind11;
using namespace dacrt;
using namespace dacrt::bindargs;

namespace {

using F32Array = py::array_t<float, py::array::c_style>;
using I32Array = py::array_t<int32_t, py::array::c_style>;
using I64Array = py::array_t<int64_t, py::array::c_style>;

// The (R, LAMP_RECORD_WIDTH) records as LampRecord rows, each checked.
const LampRecord* lamp_records(const F32Array& records) {
    if (records.ndim() != 2 || size_t(records.shape(1)) != LAMP_RECORD_WIDTH)
        throw py::value_error("records must have shape (R, " + std::to_string(LAMP_RECORD_WIDTH) + "), got " +
                              shape_str(records));
    const LampRecord* rec = reinterpret_cast<const LampRecord*>(records.data());
    for (py::ssize_t j = 0; j < records.shape(0); ++j) {
        std::string err = lamp_record_error(rec[j]);
        if (!err.empty()) throw py::value_error("records[" + std::to_string(j) + "]: " + err);
    }
    return rec;
}

const float* optional_f32(const py::object& o, py::ssize_t rows, size_t n, const char* name, F32Array& keep) {
    if (o.is_none()) return nullptr;
    keep = o.cast<F32Array>();
    need_shape(keep, rows, n, name);
    return keep.data();
}

// Whether pid (n,) ascends strictly within 0..N-1. Branch-free, so it vectorises: the loop
// that stopped at the first step down compared one pid a cycle, on the calling thread before
// every gather (0.4% of a Cornell 256 spp render's CPU samples); 500K pids 0.38 -> 0.19 ms.
__attribute__((target_clones("avx512f", "avx2", "default")))
bool pids_ascend(const int64_t* p, size_t n, size_t N) {
    if (n == 0) return true;
    uint64_t down = uint64_t(p[0] < 0) | uint64_t(uint64_t(p[n - 1]) >= uint64_t(N));
    for (size_t i = 1; i < n; ++i) down |= uint64_t(p[i] <= p[i - 1]);
    return down == 0;
}

// Gathers split threads by ray and add to L[:, pid]: pid must be in range and distinct. A
// renderer's pids ascend (compaction keeps path order): checked in one cheap pass; any other
// order gets the full check with a marker per column. Empty when fine.
std::string pid_error(const int64_t* p, size_t n, size_t N) {
    if (pids_ascend(p, n, N)) return {};
    std::vector<uint8_t> seen(N, 0);
    for (size_t i = 0; i < n; ++i) {
        if (p[i] < 0 || size_t(p[i]) >= N)
            return "pid[" + std::to_string(i) + "] = " + std::to_string(p[i]) + " is outside 0.." +
                   std::to_string(N ? N - 1 : 0) + " (L has " + std::to_string(N) + " columns)";
        if (seen[size_t(p[i])]++)
            return "pid[" + std::to_string(i) + "] = " + std::to_string(p[i]) + " repeats an earlier pid (must be distinct)";
    }
    return {};
}

// Runs gather(out, N) on L, a (3, N) array added to in place, once pid (n,) is checked, with
// the GIL released.
template <class F>
void gather_into(py::array L, const I64Array& pid, size_t n, F&& gather) {
    if (!py::isinstance<py::array_t<float>>(L) || !(L.flags() & py::array::c_style) || !L.writeable() || L.ndim() != 2 ||
        L.shape(0) != 3)
        throw py::value_error("L must be a writeable C-contiguous (3, N) float32 array (added to in place), got " +
                              shape_str(L));
    const size_t N = size_t(L.shape(1));
    float* out = static_cast<float*>(L.mutable_data());
    std::string err;
    {
        py::gil_scoped_release nogil;
        err = pid_error(pid.data(), n, N);
        if (err.empty()) gather(out, N);
    }
    if (!err.empty()) throw py::value_error(err);
}

void lamp_sample_py(F32Array records, I32Array entry, F32Array P, F32Array u1, F32Array u2, py::array wi,
                    py::array dist, py::array value, py::array pdf) {
    const LampRecord* rec = lamp_records(records);
    const size_t R = size_t(records.shape(0));
    if (P.ndim() != 2 || P.shape(0) != 3) throw py::value_error("P must have shape (3, n), got " + shape_str(P));
    const size_t n = size_t(P.shape(1));
    need_shape(entry, 0, n, "entry");
    need_shape(u1, 0, n, "u1");
    need_shape(u2, 0, n, "u2");
    float* w = out_array(wi, 3, n, "wi");
    float* d = out_array(dist, 0, n, "dist");
    float* v = out_array(value, 3, n, "value");
    float* p = out_array(pdf, 0, n, "pdf");
    py::gil_scoped_release nogil;
    lamp_sample(rec, R, entry.data(), P.data(), u1.data(), u2.data(), n, w, d, v, p);
}

// Calls f(i, P_i, N_i or null) for the n points of P (3, n) with optional normals N (3, n);
// returns n.
template <class F>
size_t for_tree_points(const F32Array& P, const py::object& N, F&& f) {
    if (P.ndim() != 2 || P.shape(0) != 3) throw py::value_error("P must have shape (3, n), got " + shape_str(P));
    const size_t n = size_t(P.shape(1));
    F32Array normal_keep;
    const float* nv = optional_f32(N, 3, n, "N", normal_keep);
    const float* p = P.data();
    for (size_t i = 0; i < n; ++i) {
        const float q[3] = {p[i], p[n + i], p[2 * n + i]};
        const float m[3] = {nv ? nv[i] : 0.0f, nv ? nv[n + i] : 0.0f, nv ? nv[2 * n + i] : 0.0f};
        f(i, q, nv ? m : nullptr);
    }
    return n;
}

// Light linking's receiver masks (n,) uint64, or null (none) when `receivers` is None.
const uint64_t* optional_receivers(const py::object& receivers, size_t n, py::array_t<uint64_t, py::array::c_style>& keep) {
    if (receivers.is_none()) return nullptr;
    keep = receivers.cast<py::array_t<uint64_t, py::array::c_style>>();
    need_shape(keep, 0, n, "receivers");
    return keep.data();
}

// rows: stop by stop, the points at a stop side by side (sample_rows, as light sampling walks
// them); else one by one (sample).
py::tuple tree_sample_py(const LightTree& t, F32Array P, py::array_t<double, py::array::c_style> u, py::object N,
                         py::object receivers, bool rows) {
    const size_t n = P.ndim() == 2 ? size_t(P.shape(1)) : 0;
    need_shape(u, 0, n, "u");
    py::array_t<uint64_t, py::array::c_style> recv_keep;
    const uint64_t* r = optional_receivers(receivers, n, recv_keep);
    py::array_t<int32_t> key(n);
    py::array_t<double> prob(n);
    if (!rows) {
        for_tree_points(P, N, [&](size_t i, const float* q, const float* m) {
            double pr;
            key.mutable_data()[i] = t.sample(q, m, u.data()[i], pr, r ? r[i] : LightTree::kAllSets);
            prob.mutable_data()[i] = pr;
        });
        return py::make_tuple(key, prob);
    }
    std::vector<float> qs(3 * n), ms(3 * n);
    bool normal = false;
    for_tree_points(P, N, [&](size_t i, const float* q, const float* m) {
        std::copy(q, q + 3, qs.begin() + long(3 * i));
        if (m) std::copy(m, m + 3, ms.begin() + long(3 * i)), normal = true;
    });
    // stop by stop (sample_rows), from rows of the points
    std::vector<float> qr(3 * n), mr(3 * n);
    for (size_t i = 0; i < n; ++i)
        for (size_t a = 0; a < 3; ++a) qr[a * n + i] = qs[3 * i + a], mr[a * n + i] = ms[3 * i + a];
    t.sample_rows(n, qr.data(), normal ? mr.data() : nullptr, n, u.data(), r, key.mutable_data(),
                  prob.mutable_data());
    return py::make_tuple(key, prob);
}

py::array_t<double> tree_pdf_py(const LightTree& t, F32Array P, I64Array key, py::object N, py::object receivers) {
    const size_t n = P.ndim() == 2 ? size_t(P.shape(1)) : 0;
    need_shape(key, 0, n, "key");
    py::array_t<uint64_t, py::array::c_style> recv_keep;
    const uint64_t* r = optional_receivers(receivers, n, recv_keep);
    py::array_t<double> prob(n);
    for_tree_points(P, N, [&](size_t i, const float* q, const float* m) {
        prob.mutable_data()[i] = t.pdf(q, m, key.data()[i], r ? r[i] : LightTree::kAllSets);
    });
    return prob;
}

// Every stop's lane weighs at one point (LightTree::stop_weighs): (lanes, exact), each (stops, 8);
// smallest: (lanes, exact) of the smallest importances instead.
py::tuple tree_stop_weighs_py(const LightTree& t, F32Array P, py::object N, bool smallest) {
    if (P.ndim() != 1 || P.shape(0) != 3) throw py::value_error("P must have shape (3,), got " + shape_str(P));
    F32Array normal_keep;
    const float* nv = optional_f32(N, 0, 3, "N", normal_keep);
    py::array_t<double> lanes({t.stops(), size_t(8)}), exact({t.stops(), size_t(8)});
    py::array_t<double> lmin({t.stops(), size_t(8)}), emin({t.stops(), size_t(8)});
    t.stop_weighs(P.data(), nv, lanes.mutable_data(), exact.mutable_data(), lmin.mutable_data(), emin.mutable_data());
    return smallest ? py::make_tuple(lmin, emin) : py::make_tuple(lanes, exact);
}

std::shared_ptr<LightTree> make_tree(F32Array lo, F32Array hi, F32Array axis, F32Array cos_o, F32Array cos_e,
                                     py::array_t<double, py::array::c_style> energy, I32Array key, py::object group,
                                     py::object set, py::object radius) {
    if (lo.ndim() != 2 || lo.shape(0) != 3) throw py::value_error("lo must have shape (3, m), got " + shape_str(lo));
    const size_t m = size_t(lo.shape(1));
    need_shape(hi, 3, m, "hi");
    need_shape(axis, 3, m, "axis");
    need_shape(cos_o, 0, m, "cos_o");
    need_shape(cos_e, 0, m, "cos_e");
    need_shape(energy, 0, m, "energy");
    need_shape(key, 0, m, "key");
    LightTreeInput in{lo.data(), hi.data(), axis.data(), cos_o.data(), cos_e.data(), energy.data(), key.data(), m};
    I32Array group_keep;
    if (!group.is_none()) {
        group_keep = group.cast<I32Array>();
        need_shape(group_keep, 0, m, "group");
        in.group = group_keep.data();
    }
    py::array_t<uint8_t, py::array::c_style> set_keep;
    if (!set.is_none()) {
        set_keep = set.cast<py::array_t<uint8_t, py::array::c_style>>();
        need_shape(set_keep, 0, m, "set");
        in.set = set_keep.data();
    }
    F32Array radius_keep;
    if (!radius.is_none()) {
        radius_keep = radius.cast<F32Array>();
        need_shape(radius_keep, 0, m, "radius");
        in.radius = radius_keep.data();
    }
    py::gil_scoped_release nogil;
    return std::make_shared<LightTree>(in);  // it validates: std::invalid_argument is ValueError
}

// Which of n rays missed (missflags.h): bool flags, or the tracer's (n,) hit records
// (dacrt.HIT_DTYPE), read in place as prim < 0 so that the caller makes no flags from them.
// keep holds the flags' array.
Missed missed_arg(const py::object& miss, size_t n, py::array_t<bool, py::array::c_style>& keep) {
    if (py::isinstance<py::array>(miss)) {
        const py::array a = miss.cast<py::array>();
        const py::object fields = a.dtype().attr("fields");
        if (!fields.is_none()) {  // structured: it must be the hit records
            const py::tuple prim = fields.contains("prim") ? fields["prim"].cast<py::tuple>() : py::tuple();
            const bool prim_at = prim.size() >= 2 && prim[0].cast<py::dtype>().kind() == 'i' &&
                                 prim[0].cast<py::dtype>().itemsize() == 4 &&
                                 prim[1].cast<size_t>() == offsetof(Hit, prim);
            if (!prim_at || a.ndim() != 1 || a.itemsize() != sizeof(Hit) || !(a.flags() & py::array::c_style))
                throw py::value_error("miss must be bool flags or a contiguous (n,) array of the tracer's " +
                                      std::to_string(sizeof(Hit)) + "-byte hit records (HIT_DTYPE), got " +
                                      shape_str(a) + " of " + py::str(a.dtype()).cast<std::string>());
            need_shape(a, 0, n, "miss");
            return Missed{nullptr, static_cast<const Hit*>(a.data())};
        }
    }
    keep = miss.cast<py::array_t<bool, py::array::c_style>>();
    need_shape(keep, 0, n, "miss");
    return Missed{reinterpret_cast<const uint8_t*>(keep.data()), nullptr};
}

void lamp_gather_py(F32Array records, I32Array lamps, py::object lamp_prob, F32Array O, F32Array D,
                    py::array_t<float> t_surf, py::object miss, py::object thr,
                    py::object pdf_bsdf, I64Array pid, py::array L, float clamp, py::object tree, py::object lamp_key,
                    py::object normal, py::object receivers) {
    check_clamp(clamp);
    const LampRecord* rec = lamp_records(records);
    const size_t R = size_t(records.shape(0));
    if (lamps.ndim() != 1) throw py::value_error("lamps must be one-dimensional, got " + shape_str(lamps));
    const size_t nl = size_t(lamps.shape(0));
    // a private copy, checked: the kernel then reads no caller index another thread may rewrite
    const std::vector<int32_t> lamp_list(lamps.data(), lamps.data() + nl);
    for (size_t k = 0; k < nl; ++k)
        if (lamp_list[k] < 0 || size_t(lamp_list[k]) >= R)
            throw py::value_error("lamps[" + std::to_string(k) + "] = " + std::to_string(lamp_list[k]) +
                                  " is not a record index 0.." + std::to_string(R ? R - 1 : 0));
    if (lamp_prob.is_none() != pdf_bsdf.is_none())
        throw py::value_error("lamp_prob and pdf_bsdf go together: both for BSDF rays (MIS), neither for camera rays");
    if (O.ndim() != 2 || O.shape(0) != 3) throw py::value_error("O must have shape (3, n), got " + shape_str(O));
    const size_t n = size_t(O.shape(1));
    need_shape(D, 3, n, "D");
    need_shape(t_surf, 0, n, "t_surf");
    // t_surf read in place with its stride when it is a whole number of floats (the t field of
    // the tracer's hit records, hits['t']: a copy of it had cost ~1.5 ms of a Cornell 64 spp
    // render), else copied contiguous
    const py::ssize_t t_bytes = t_surf.strides(0);
    const bool aligned = reinterpret_cast<uintptr_t>(t_surf.data()) % alignof(float) == 0;
    if (!aligned || !(n < 2 || (t_bytes > 0 && t_bytes % py::ssize_t(sizeof(float)) == 0)))
        t_surf = py::array_t<float, py::array::c_style>::ensure(t_surf);
    const size_t t_step = n < 2 ? 1 : size_t(t_surf.strides(0)) / sizeof(float);
    // miss is read for the lamps at infinity alone: without one it may be None (the caller
    // then makes no flags from the hit records)
    py::array_t<bool, py::array::c_style> miss_keep;
    Missed missed;
    if (!miss.is_none()) {
        missed = missed_arg(miss, n, miss_keep);
    } else {
        for (size_t k = 0; k < nl; ++k)
            if (at_infinity(rec[lamp_list[k]]))
                throw py::value_error("miss is None, but lamps[" + std::to_string(k) + "] = " +
                                      std::to_string(lamp_list[k]) +
                                      " is at infinity (a sun or the background): it needs which rays missed");
    }
    need_shape(pid, 0, n, "pid");
    F32Array prob_keep, thr_keep, pdf_keep;
    const float* prob = optional_f32(lamp_prob, 0, R, "lamp_prob", prob_keep);
    const float* t = optional_f32(thr, 3, n, "thr", thr_keep);
    const float* pb = optional_f32(pdf_bsdf, 0, n, "pdf_bsdf", pdf_keep);
    I32Array key_keep;
    const LightTree* lt = tree_keys(tree, lamp_key, R, "lamp_key", key_keep);
    F32Array normal_keep;
    const float* nv = optional_f32(normal, 3, n, "normal", normal_keep);
    py::array_t<uint64_t, py::array::c_style> recv_keep;
    const uint64_t* recv = optional_receivers(receivers, n, recv_keep);
    gather_into(L, pid, n, [&](float* out, size_t N) {
        lamp_gather(rec, lamp_list.data(), nl, prob, O.data(), D.data(), t_surf.data(),
                    missed, t, pb, pid.data(), n, out, N, clamp, lt,
                    lt ? key_keep.data() : nullptr, nv, recv, t_step);
    });
}

py::dict lamp_record_layout() {
    py::dict d;
#define DACRT_FIELD(f, width) d[#f] = py::make_tuple(offsetof(LampRecord, f) / sizeof(float), width)
    DACRT_FIELD(kind, 1);
    DACRT_FIELD(shape, 1);
    DACRT_FIELD(emit, 3);
    DACRT_FIELD(pos, 3);
    DACRT_FIELD(radius, 1);
    DACRT_FIELD(cos_half, 1);
    DACRT_FIELD(inv_smooth, 1);
    DACRT_FIELD(omc, 1);
    DACRT_FIELD(pdf, 1);
    DACRT_FIELD(area, 1);
    DACRT_FIELD(axis_x, 3);
    DACRT_FIELD(axis_y, 3);
    DACRT_FIELD(inv_x, 3);
    DACRT_FIELD(inv_y, 3);
    DACRT_FIELD(normal, 3);
    DACRT_FIELD(tan_half_spread, 1);
    DACRT_FIELD(spread_norm, 1);
    DACRT_FIELD(inv_m3, 9);
    DACRT_FIELD(ies, 1);
    DACRT_FIELD(ies_m3, 9);
    DACRT_FIELD(falloff_power, 1);
    DACRT_FIELD(falloff_smooth, 1);
#undef DACRT_FIELD
    return d;
}

// The per-entry tables of a light choice over R lamp records and T emissive triangles.
LightChoice light_choice(const F32Array& records, const py::array_t<double, py::array::c_style>& cdf,
                         const F32Array& prob, const py::array_t<bool, py::array::c_style>& no_mis,
                         const py::array_t<bool, py::array::c_style>& shadow, const py::object& tri_geo,
                         const py::object& tri_area, const py::object& tri_emission, const py::object& env,
                         std::shared_ptr<EnvironmentMap>& env_keep, F32Array keep[3]) {
    LightChoice c{};
    c.lamps = lamp_records(records);
    c.num_lamps = size_t(records.shape(0));
    if (tri_geo.is_none() != tri_area.is_none() || tri_geo.is_none() != tri_emission.is_none())
        throw py::value_error("tri_geo, tri_area and tri_emission go together (all None: no emissive triangles)");
    if (!tri_geo.is_none()) {
        keep[0] = tri_geo.cast<F32Array>();
        if (keep[0].ndim() != 2 || keep[0].shape(0) != 15)
            throw py::value_error("tri_geo must have shape (15, T), got " + shape_str(keep[0]));
        c.num_tris = size_t(keep[0].shape(1));
        c.tri_geo = keep[0].data();
        c.tri_area = optional_f32(tri_area, 0, c.num_tris, "tri_area", keep[1]);
        c.tri_emission = optional_f32(tri_emission, 3, c.num_tris, "tri_emission", keep[2]);
    }
    if (!env.is_none()) {
        env_keep = env.cast<std::shared_ptr<EnvironmentMap>>();
        c.env = env_keep.get();
    }
    c.entries = c.num_lamps + c.num_tris + (c.env ? 1 : 0);
    if (c.entries == 0) throw py::value_error("there is no light to choose (no lamp records, no triangles)");
    need_shape(cdf, 0, c.entries, "cdf");
    need_shape(prob, 0, c.entries, "prob");
    need_shape(no_mis, 0, c.entries, "no_mis");
    need_shape(shadow, 0, c.entries, "shadow");
    c.cdf = cdf.data();
    c.prob = prob.data();
    c.no_mis = reinterpret_cast<const uint8_t*>(no_mis.data());
    c.shadow = reinterpret_cast<const uint8_t*>(shadow.data());
    return c;
}

// A light tree over the choice's entries, or none; with one, the cdf's runs (choiceruns.h): its
// members other than the first have no mass of their own, so the runs are few. given: the
// runs as choice_runs_py made them (run_cdf, run_entry), checked against the cdf in O(runs),
// or None: built here (into runs), which reads every entry.
void attach_tree(LightChoice& c, const py::object& tree, const py::object& given, ChoiceRuns& runs,
                 py::array_t<double, py::array::c_style>& keep_cdf, py::array_t<uint32_t, py::array::c_style>& keep_entry) {
    if (tree.is_none()) return;
    c.tree = tree.cast<const LightTree*>();
    if (c.tree->key_bound() > c.entries)
        throw py::value_error("the light tree's keys must be entries of the light choice (0.." +
                              std::to_string(c.entries - 1) + ")");
    if (given.is_none()) {
        choice_runs(c.cdf, c.entries, runs);
        c.run_cdf = runs.cdf.data();
        c.run_entry = runs.entry.data();
        c.runs = runs.cdf.size();
        return;
    }
    const py::tuple t = given.cast<py::tuple>();
    if (t.size() != 2) throw py::value_error("runs is (run_cdf, run_entry), as choice_runs gives them");
    keep_cdf = t[0].cast<py::array_t<double, py::array::c_style>>();
    keep_entry = t[1].cast<py::array_t<uint32_t, py::array::c_style>>();
    if (keep_cdf.ndim() != 1) throw py::value_error("run_cdf must be one-dimensional, got " + shape_str(keep_cdf));
    const size_t r = size_t(keep_cdf.shape(0));
    need_shape(keep_entry, 0, r, "run_entry");
    const std::string err = choice_runs_error(c.cdf, c.entries, keep_cdf.data(), keep_entry.data(), r);
    if (!err.empty()) throw py::value_error("runs are not the cdf's (choice_runs(cdf) makes them): " + err);
    c.run_cdf = keep_cdf.data();
    c.run_entry = keep_entry.data();
    c.runs = r;
}

// choice_runs of cdf (float64, (n,)): (run_cdf (r,) float64, run_entry (r,) uint32), empty where
// the cdf is not non-decreasing or holds a NaN.
py::tuple choice_runs_py(py::array_t<double, py::array::c_style> cdf) {
    if (cdf.ndim() != 1) throw py::value_error("cdf must be one-dimensional, got " + shape_str(cdf));
    ChoiceRuns runs;
    choice_runs(cdf.data(), size_t(cdf.shape(0)), runs);
    py::array_t<double> run_cdf(py::ssize_t(runs.cdf.size()));
    py::array_t<uint32_t> run_entry(py::ssize_t(runs.entry.size()));
    std::copy(runs.cdf.begin(), runs.cdf.end(), run_cdf.mutable_data());
    std::copy(runs.entry.begin(), runs.entry.end(), run_entry.mutable_data());
    return py::make_tuple(run_cdf, run_entry);
}

// The emissive triangles' primitive ids (None: not given).
const int32_t* tri_prims(const py::object& tri_prim, size_t num_tris, I32Array& keep) {
    if (tri_prim.is_none()) return nullptr;
    keep = tri_prim.cast<I32Array>();
    need_shape(keep, 0, num_tris, "tri_prim");
    return keep.data();
}

// The light-choice uniforms of n points, needed when there is more than one light.
const double* pick_uniforms(const py::object& pick, size_t n, size_t entries,
                            py::array_t<double, py::array::c_style>& keep) {
    if (pick.is_none()) {
        if (entries > 1) throw py::value_error("pick (the light-choice uniforms) is needed with more than one light");
        return nullptr;
    }
    keep = pick.cast<py::array_t<double, py::array::c_style>>();
    need_shape(keep, 0, n, "pick");
    return keep.data();
}

py::tuple next_event_py(F32Array records, py::array_t<double, py::array::c_style> cdf, F32Array prob,
                     py::array_t<bool, py::array::c_style> no_mis, py::array_t<bool, py::array::c_style> shadow,
                     py::object tri_geo, py::object tri_area, py::object tri_emission, py::object env, F32Array P,
                     F32Array P_off,
                     F32Array ns, py::object ng, py::object thr, py::array_t<uint32_t, py::array::c_style> keys,
                     uint32_t ka, uint32_t kb, py::object pick, py::object prim, float shorten, bool skip_work,
                     py::array value, py::array_t<bool, py::array::c_style> contrib, py::array rays,
                     py::array_t<int64_t, py::array::c_style> send, py::object skip, py::object terminator,
                     py::object linking, py::object entry, py::object point, py::object bump, py::object tree,
                     py::object tri_prim, py::object rough, py::object runs_given) {
    F32Array keep[3], ng_keep, thr_keep, bump_keep, rough_keep;
    std::shared_ptr<EnvironmentMap> env_keep;
    LightChoice lights =
        light_choice(records, cdf, prob, no_mis, shadow, tri_geo, tri_area, tri_emission, env, env_keep, keep);
    ChoiceRuns runs;
    py::array_t<double, py::array::c_style> run_cdf_keep;
    py::array_t<uint32_t, py::array::c_style> run_entry_keep;
    attach_tree(lights, tree, runs_given, runs, run_cdf_keep, run_entry_keep);
    if (P.ndim() != 2 || P.shape(0) != 3) throw py::value_error("P must have shape (3, n), got " + shape_str(P));
    VertexPoints pts{};
    pts.n = size_t(P.shape(1));
    const size_t n = pts.n;
    need_shape(P_off, 3, n, "P_off");
    need_shape(ns, 3, n, "ns");
    need_shape(keys, 2, n, "keys");
    pts.P = P.data();
    pts.P_off = P_off.data();
    pts.ns = ns.data();
    pts.ng = optional_f32(ng, 3, n, "ng", ng_keep);
    pts.thr = optional_f32(thr, 3, n, "thr", thr_keep);
    pts.bump = optional_f32(bump, 4, n, "bump", bump_keep);
    pts.rough = optional_f32(rough, kRoughRows, n, "rough", rough_keep);
    pts.keys = keys.data();
    pts.ka = ka;
    pts.kb = kb;
    py::array_t<double, py::array::c_style> pick_keep;
    pts.pick = pick_uniforms(pick, n, lights.entries, pick_keep);
    I32Array prim_keep, tri_prim_keep;
    if (!prim.is_none()) {
        prim_keep = prim.cast<I32Array>();
        need_shape(prim_keep, 0, n, "prim");
        pts.prim = prim_keep.data();
    }
    lights.tri_prim = tri_prims(tri_prim, lights.num_tris, tri_prim_keep);
    pts.shorten = shorten;
    pts.skip_work = skip_work;
    py::array_t<uint8_t, py::array::c_style> set_keep;
    py::array_t<uint64_t, py::array::c_style> recv_keep;
    if (!linking.is_none()) {
        const py::tuple t = linking.cast<py::tuple>();
        if (t.size() != 2) throw py::value_error("linking is (light_set, receivers)");
        set_keep = t[0].cast<py::array_t<uint8_t, py::array::c_style>>();
        need_shape(set_keep, 0, lights.entries, "linking light_set");
        for (size_t e = 0; e < lights.entries; ++e)
            if (set_keep.data()[e] > 63)
                throw py::value_error("linking light_set[" + std::to_string(e) + "] must be a light set 0..63");
        recv_keep = t[1].cast<py::array_t<uint64_t, py::array::c_style>>();
        need_shape(recv_keep, 0, n, "linking receivers");
        lights.light_set = set_keep.data();
        pts.receivers = recv_keep.data();
    }
    Terminator term{};
    F32Array term_keep[6];
    if (!terminator.is_none()) {
        if (!pts.prim) throw py::value_error("terminator needs prim");
        const py::tuple t = terminator.cast<py::tuple>();
        if (t.size() != 6) throw py::value_error("terminator is (geo, normals, cutoff, freq, u, v)");
        term_keep[0] = t[0].cast<F32Array>();
        if (term_keep[0].ndim() != 2 || term_keep[0].shape(0) != 15)
            throw py::value_error("terminator geo must have shape (15, M), got " + shape_str(term_keep[0]));
        term.M = size_t(term_keep[0].shape(1));
        if (term.M == 0) throw py::value_error("terminator geo has no triangles");
        check_index(pts.prim, n, term.M, "prim");
        term.geo = term_keep[0].data();
        term.normals = optional_f32(t[1], 9, term.M, "terminator normals", term_keep[1]);
        term.cutoff = optional_f32(t[2], 0, term.M, "terminator cutoff", term_keep[2]);
        term.freq = optional_f32(t[3], 0, term.M, "terminator freq", term_keep[3]);
        term.u = optional_f32(t[4], 0, n, "terminator u", term_keep[4]);
        term.v = optional_f32(t[5], 0, n, "terminator v", term_keep[5]);
        if (term.cutoff && (!term.normals || !term.u || !term.v))
            throw py::value_error("a terminator cutoff needs the corner normals and the points' u and v");
        pts.term = &term;
    }
    NextEventOut out{};
    out.value = out_array(value, 3, n, "value");
    if (!contrib.writeable()) throw py::value_error("contrib must be writeable");
    need_shape(contrib, 0, n, "contrib");
    out.contrib = reinterpret_cast<uint8_t*>(contrib.mutable_data());
    py::array_t<int32_t, py::array::c_style> entry_keep;
    if (!entry.is_none()) {
        entry_keep = entry.cast<py::array_t<int32_t, py::array::c_style>>();
        if (!entry_keep.writeable() || entry_keep.ptr() != entry.ptr())
            throw py::value_error("entry must be a writeable C-contiguous int32 array (written in place)");
        need_shape(entry_keep, 0, n, "entry");
        out.entry = entry_keep.mutable_data();
    }
    F32Array point_keep;
    if (!point.is_none()) {
        point_keep = point.cast<F32Array>();
        if (!point_keep.writeable() || point_keep.ptr() != point.ptr())
            throw py::value_error("point must be a writeable C-contiguous float32 array (written in place)");
        need_shape(point_keep, 3, n, "point");
        out.point = point_keep.mutable_data();
    }
    if (rays.ndim() != 1 || size_t(rays.shape(0)) != n || rays.itemsize() != sizeof(Ray) ||
        !(rays.flags() & py::array::c_style) || !rays.writeable())
        throw py::value_error("rays must be a writeable contiguous (" + std::to_string(n) + ",) array of ray records");
    out.rays = static_cast<Ray*>(rays.mutable_data());
    if (!send.writeable()) throw py::value_error("send must be writeable");
    need_shape(send, 0, n, "send");
    out.send = send.mutable_data();
    I32Array skip_keep;
    if (!skip.is_none()) {
        if (!pts.prim) throw py::value_error("skip (the triangle each shadow ray leaves) needs prim");
        skip_keep = skip.cast<I32Array>();
        if (!skip_keep.writeable()) throw py::value_error("skip must be writeable");
        need_shape(skip_keep, 0, n, "skip");
        out.skip = skip_keep.mutable_data();
    }
    size_t m, bad;
    {
        py::gil_scoped_release nogil;
        m = next_event(lights, pts, out, &bad);
    }
    return py::make_tuple(m, bad);
}

// A diffuse vertex shaded in one pass (bounce.h): survivors, their throughputs and surface
// points, light samples with shadow rays and (scatter) bounce directions with their rays. The
// lights as next_event_py takes them; ray_dtype: the records' dtype for the rays created here.
py::tuple shade_bounce_py(F32Array records, py::array_t<double, py::array::c_style> cdf, F32Array prob,
                          py::array_t<bool, py::array::c_style> no_mis, py::array_t<bool, py::array::c_style> shadow,
                          py::object tri_geo, py::object tri_area, py::object tri_emission, py::object env,
                          py::object tree, py::object tri_prim, py::array hits, py::object hit,
                          py::array_t<bool, py::array::c_style> live, F32Array albedo, py::object thr, py::object u_rr,
                          F32Array geo, py::object normals, F32Array D, I64Array pid,
                          py::array_t<uint32_t, py::array::c_style> keys, py::object pick, uint32_t nee_ka,
                          uint32_t nee_kb, float shorten, bool skip_work, bool scatter, uint32_t ka, uint32_t kb,
                          py::object ray_dtype, py::object rough, py::object records_of_geo, py::object runs_given,
                          py::object draw) {
    F32Array keep[3];
    std::shared_ptr<EnvironmentMap> env_keep;
    LightChoice lights =
        light_choice(records, cdf, prob, no_mis, shadow, tri_geo, tri_area, tri_emission, env, env_keep, keep);
    ChoiceRuns runs;
    py::array_t<double, py::array::c_style> run_cdf_keep;
    py::array_t<uint32_t, py::array::c_style> run_entry_keep;
    attach_tree(lights, tree, runs_given, runs, run_cdf_keep, run_entry_keep);
    I32Array tri_prim_keep;
    lights.tri_prim = tri_prims(tri_prim, lights.num_tris, tri_prim_keep);
    BounceIn in{};
    in.n = hits.ndim() == 1 ? size_t(hits.shape(0)) : 0;
    const size_t n = in.n;
    if (hits.ndim() != 1 || hits.itemsize() != sizeof(Hit) || !(hits.flags() & py::array::c_style))
        throw py::value_error("hits must be a contiguous (n,) array of " + std::to_string(sizeof(Hit)) +
                              "-byte records");
    in.hits = static_cast<const Hit*>(hits.data());
    py::array_t<bool, py::array::c_style> hit_keep;
    if (!hit.is_none()) {  // (None: the hits are the records with prim >= 0, read in the pass)
        hit_keep = hit.cast<py::array_t<bool, py::array::c_style>>();
        need_shape(hit_keep, 0, n, "hit");
        in.hit = reinterpret_cast<const uint8_t*>(hit_keep.data());
    }
    if (live.ndim() != 1) throw py::value_error("live must be one-dimensional");
    in.M = size_t(live.shape(0));
    in.live = reinterpret_cast<const uint8_t*>(live.data());
    need_shape(albedo, 3, in.M, "albedo");
    in.albedo = albedo.data();
    F32Array thr_keep, rr_keep, nrm_keep;
    in.thr = optional_f32(thr, 3, n, "thr", thr_keep);
    in.u_rr = optional_f32(u_rr, 0, n, "u_rr", rr_keep);
    need_shape(geo, 15, in.M, "geo");
    in.geo = geo.data();
    in.normals = optional_f32(normals, 9, in.M, "normals", nrm_keep);
    F32Array rec_keep;
    in.records = hit_records_arg(records_of_geo, in.M, in.normals != nullptr, rec_keep);
    need_shape(D, 3, n, "D");
    in.D = D.data();
    need_shape(pid, 0, n, "pid");
    in.pid = pid.data();
    need_shape(keys, 2, n, "keys");
    in.keys = keys.data();
    if (!draw.is_none()) {  // (ka, kb, pick, roulette): uniform_pick's uniforms drawn in the pass
        const auto t = draw.cast<py::tuple>();
        if (t.size() != 4) throw py::value_error("draw must be (ka, kb, pick, roulette)");
        if (!u_rr.is_none() || !pick.is_none()) throw py::value_error("draw takes the place of u_rr and pick");
        in.draw_ka = t[0].cast<uint32_t>(), in.draw_kb = t[1].cast<uint32_t>();
        in.draw_pick = t[2].cast<bool>(), in.draw_rr = t[3].cast<bool>();
    }
    py::array_t<double, py::array::c_style> pick_keep;
    if (!in.draw_pick) in.pick = pick_uniforms(pick, n, lights.entries, pick_keep);
    in.nee_ka = nee_ka, in.nee_kb = nee_kb, in.shorten = shorten, in.skip_work = skip_work;
    in.scatter = scatter, in.ka = ka, in.kb = kb;
    I32Array rough_mat_keep;
    F32Array rough_params_keep, rough_rho_keep;
    if (!rough.is_none()) {  // (triangle materials (M,), params (4, m), colours (3, m))
        const auto t = rough.cast<py::tuple>();
        if (t.size() != 3) throw py::value_error("rough must be (materials, params, colours)");
        rough_mat_keep = t[0].cast<I32Array>();
        rough_params_keep = t[1].cast<F32Array>();
        rough_rho_keep = t[2].cast<F32Array>();
        need_shape(rough_mat_keep, 0, in.M, "rough materials");
        if (rough_params_keep.ndim() != 2 || rough_params_keep.shape(0) != 4)
            throw py::value_error("rough params must have shape (4, m)");
        in.rough_M = size_t(rough_params_keep.shape(1));
        need_shape(rough_rho_keep, 3, in.rough_M, "rough colours");
        const int32_t* m = rough_mat_keep.data();
        for (size_t i = 0; i < in.M; ++i)
            if (m[i] < 0 || size_t(m[i]) >= in.rough_M) throw py::value_error("rough materials out of range");
        in.rough_mat = m;
        in.rough_params = rough_params_keep.data();
        in.rough_rho = rough_rho_keep.data();
    }
    const py::dtype rd = py::dtype::from_args(ray_dtype);
    if (size_t(rd.itemsize()) != sizeof(Ray)) throw py::value_error("ray_dtype must describe the tracer's ray records");
    I64Array idx{py::ssize_t(n)};
    size_t k, black, rr;
    {
        py::gil_scoped_release nogil;
        k = in.draw_rr ? survivors_drawn(in.hits, in.hit, n, in.live, in.M, in.thr, in.keys, in.draw_ka, in.draw_kb,
                                      idx.mutable_data(), &black, &rr)
                    : survivors(in.hits, in.hit, n, in.live, in.M, in.thr, in.u_rr, idx.mutable_data(), &black, &rr);
    }
    const py::ssize_t K = py::ssize_t(k);
    F32Array thr_out({py::ssize_t(3), K}), surf({py::ssize_t(in.normals ? 12 : 9), K});
    I32Array prim{K};
    I64Array pid_out{K};
    py::array_t<uint32_t> keys_out({py::ssize_t(2), K});
    py::object pick_out = py::none();
    py::array_t<double> pick_arr;
    if (in.pick || in.draw_pick) {
        pick_arr = py::array_t<double>(K);
        pick_out = pick_arr;
    }
    F32Array value({py::ssize_t(3), K});
    py::array_t<bool> contrib{K};
    py::array shadow_rays(rd, std::vector<py::ssize_t>{K});
    I64Array send{K};
    I32Array skip{K};
    F32Array wi, pdf;
    py::array_t<bool> ok;
    py::array rays;
    BounceOut out{};
    out.thr = thr_out.mutable_data();
    out.surf = surf.mutable_data();
    out.prim = prim.mutable_data();
    out.pid = pid_out.mutable_data();
    out.keys = keys_out.mutable_data();
    out.pick = in.pick || in.draw_pick ? pick_arr.mutable_data() : nullptr;
    out.nee.value = value.mutable_data();
    out.nee.contrib = reinterpret_cast<uint8_t*>(contrib.mutable_data());
    out.nee.rays = static_cast<Ray*>(shadow_rays.mutable_data());
    out.nee.send = send.mutable_data();
    out.nee.skip = skip.mutable_data();
    if (scatter) {
        wi = F32Array({py::ssize_t(3), K});
        pdf = F32Array(K);
        ok = py::array_t<bool>(K);
        rays = py::array(rd, std::vector<py::ssize_t>{K});
        out.wi = wi.mutable_data();
        out.pdf = pdf.mutable_data();
        out.ok = reinterpret_cast<uint8_t*>(ok.mutable_data());
        out.rays = static_cast<Ray*>(rays.mutable_data());
    }
    size_t m, bad;
    {
        py::gil_scoped_release nogil;
        m = shade_bounce(in, lights, idx.data(), k, out, &bad);
    }
    py::tuple paths = py::make_tuple(thr_out, surf, prim, pid_out, keys_out, pick_out);
    py::tuple nee = py::make_tuple(value, contrib, shadow_rays, send, skip, m, bad);
    py::object bsdf = scatter ? py::object(py::make_tuple(wi, pdf, ok, rays)) : py::object(py::none());
    return py::make_tuple(black, rr, paths, nee, bsdf);
}

void accumulate_masked_py(py::array L, I64Array pid, F32Array values, py::array_t<bool, py::array::c_style> mask,
                          float clamp) {
    check_clamp(clamp);
    if (L.ndim() != 2 || L.shape(0) != 3) throw py::value_error("L must have shape (3, N), got " + shape_str(L));
    const size_t N = size_t(L.shape(1));
    float* l = out_array(L, 3, N, "L");
    if (pid.ndim() != 1) throw py::value_error("pid must be one-dimensional, got " + shape_str(pid));
    const size_t n = size_t(pid.shape(0));
    need_shape(values, 3, n, "values");
    need_shape(mask, 0, n, "mask");
    bool ok;
    {
        py::gil_scoped_release nogil;
        ok = accumulate_masked(l, N, pid.data(), values.data(), reinterpret_cast<const uint8_t*>(mask.data()), n,
                               clamp);
    }
    if (!ok) throw py::value_error("pid holds a column outside 0.." + std::to_string(N ? N - 1 : 0) + " (L has " +
                                   std::to_string(N) + ")");
}

// --- the environment map (environment.h) ---

// rgb: float32, or uint8 (an 8-bit image's bytes: texel value k / 255, envbuild.h).
std::shared_ptr<EnvironmentMap> make_environment(py::array rgb, F32Array to_map, bool closest, bool srgb,
                                                 py::object scale) {
    const bool bytes = py::isinstance<py::array_t<uint8_t>>(rgb);
    rgb = bytes ? py::array(py::array_t<uint8_t, py::array::c_style>::ensure(rgb)) : py::array(F32Array::ensure(rgb));
    if (!rgb) throw py::value_error("rgb must be float32 or uint8 texels");
    if (rgb.ndim() != 3 || rgb.shape(2) < 3)
        throw py::value_error("rgb must have shape (h, w, 3 or more), got " + shape_str(rgb));
    if (to_map.ndim() != 2 || to_map.shape(0) != 3 || to_map.shape(1) != 3)
        throw py::value_error("to_map must have shape (3, 3), got " + shape_str(to_map));
    if (rgb.shape(0) > py::ssize_t(UINT32_MAX) || rgb.shape(1) > py::ssize_t(UINT32_MAX))
        throw py::value_error("the environment map is too large: " + shape_str(rgb));
    F32Array scale_keep;
    const float* sc = nullptr;
    if (!scale.is_none()) {
        scale_keep = scale.cast<F32Array>();
        if (scale_keep.ndim() != 1 || scale_keep.shape(0) != 3)
            throw py::value_error("scale must have shape (3,), got " + shape_str(scale_keep));
        sc = scale_keep.data();
    }
    auto env = std::make_shared<EnvironmentMap>();
    std::string err;
    {
        py::gil_scoped_release nogil;
        if (bytes)
            err = build_environment_bytes(*env, static_cast<const uint8_t*>(rgb.data()), size_t(rgb.shape(2)),
                                          uint32_t(rgb.shape(1)), uint32_t(rgb.shape(0)), to_map.data(), closest,
                                          srgb, sc);
        else
            err = build_environment_texels(*env, static_cast<const float*>(rgb.data()), size_t(rgb.shape(2)),
                                           uint32_t(rgb.shape(1)), uint32_t(rgb.shape(0)), to_map.data(), closest,
                                           srgb, sc);
    }
    if (!err.empty()) throw py::value_error("environment map: " + err);
    return env;
}

// (non-finite texel count, a finite value negative, a value positive) of texels (..., c >= 3):
// envbuild.h texel_stats.
py::tuple texel_stats_py(F32Array texels) {
    if (texels.ndim() < 1 || texels.shape(texels.ndim() - 1) < 3)
        throw py::value_error("texels must have 3 or more channels in their last axis, got " + shape_str(texels));
    const size_t c = size_t(texels.shape(texels.ndim() - 1)), n = size_t(texels.size()) / c;
    TexelStats f;
    {
        py::gil_scoped_release nogil;
        f = texel_stats(texels.data(), n, c);
    }
    return py::make_tuple(f.non_finite, f.negative, f.positive);
}

py::tuple environment_eval_py(const EnvironmentMap& env, F32Array D) {
    if (D.ndim() != 2 || D.shape(0) != 3) throw py::value_error("D must have shape (3, n), got " + shape_str(D));
    const size_t n = size_t(D.shape(1));
    F32Array Le({py::ssize_t(3), py::ssize_t(n)}), pdf{py::ssize_t(n)};
    float* le = Le.mutable_data();
    float* p = pdf.mutable_data();
    const float* d = D.data();
    {
        py::gil_scoped_release nogil;
        for (size_t i = 0; i < n; ++i) {
            const float di[3] = {d[i], d[n + i], d[2 * n + i]};
            float l[3];
            environment_eval(env, di, l, p[i]);
            for (int a = 0; a < 3; ++a) le[size_t(a) * n + i] = l[a];
        }
    }
    return py::make_tuple(Le, pdf);
}

// environment_sample point by point, or environment_sample_lanes over the whole arrays (the lane
// path event_block takes): tests compare the two bit for bit.
py::tuple environment_sample_py(const EnvironmentMap& env, F32Array u1, F32Array u2, bool lanes) {
    if (u1.ndim() != 1) throw py::value_error("u1 must be one-dimensional, got " + shape_str(u1));
    const size_t n = size_t(u1.shape(0));
    need_shape(u2, 0, n, "u2");
    F32Array wi({py::ssize_t(3), py::ssize_t(n)}), value({py::ssize_t(3), py::ssize_t(n)}), pdf{py::ssize_t(n)};
    float* w = wi.mutable_data();
    float* v = value.mutable_data();
    float* p = pdf.mutable_data();
    const float *a1 = u1.data(), *a2 = u2.data();
    {
        py::gil_scoped_release nogil;
        if (lanes) {
            environment_sample_lanes(env, a1, a2, n, w, v, p, n);
        } else {
            for (size_t i = 0; i < n; ++i) {
                float wv[3], vv[3];
                environment_sample(env, a1[i], a2[i], wv, vv, p[i]);
                for (int a = 0; a < 3; ++a) w[size_t(a) * n + i] = wv[a], v[size_t(a) * n + i] = vv[a];
            }
        }
    }
    return py::make_tuple(wi, value, pdf);
}

void environment_gather_py(const EnvironmentMap& env, float prob, F32Array D, py::object miss,
                           py::object thr, py::object pdf_bsdf, I64Array pid, py::array L, float clamp) {
    check_clamp(clamp);
    if (!(prob >= 0 && prob <= 1)) throw py::value_error("prob must be in [0, 1], got " + std::to_string(prob));
    if ((prob > 0) == pdf_bsdf.is_none())
        throw py::value_error("prob > 0 (BSDF rays, MIS) needs pdf_bsdf; prob 0 (camera rays) takes none");
    if (D.ndim() != 2 || D.shape(0) != 3) throw py::value_error("D must have shape (3, n), got " + shape_str(D));
    const size_t n = size_t(D.shape(1));
    py::array_t<bool, py::array::c_style> miss_keep;
    const Missed missed = missed_arg(miss, n, miss_keep);
    need_shape(pid, 0, n, "pid");
    F32Array thr_keep, pdf_keep;
    const float* t = optional_f32(thr, 3, n, "thr", thr_keep);
    const float* pb = optional_f32(pdf_bsdf, 0, n, "pdf_bsdf", pdf_keep);
    gather_into(L, pid, n, [&](float* out, size_t N) {
        environment_gather(env, prob, D.data(), missed, t, pb, pid.data(), n, out, N, clamp);
    });
}

// The equirectangular mapping's kernels alone (envlanes.h, equirect.h), for their tests.
py::tuple equirect_uv_py(F32Array to_map, F32Array D) {
    if (to_map.size() != 9) throw py::value_error("to_map must hold 9 floats, got " + shape_str(to_map));
    if (D.ndim() != 2 || D.shape(0) != 3) throw py::value_error("D must have shape (3, n), got " + shape_str(D));
    const size_t n = size_t(D.shape(1));
    F32Array u{py::ssize_t(n)}, v{py::ssize_t(n)}, s{py::ssize_t(n)};
    {
        py::gil_scoped_release nogil;
        equirect_uv_lanes(to_map.data(), D.data(), D.data() + n, D.data() + 2 * n, n, u.mutable_data(),
                          v.mutable_data(), s.mutable_data());
    }
    return py::make_tuple(u, v, s);
}

py::tuple equirect_direction_py(F32Array u, F32Array v) {
    if (u.ndim() != 1) throw py::value_error("u must be one-dimensional, got " + shape_str(u));
    const size_t n = size_t(u.shape(0));
    need_shape(v, 0, n, "v");
    F32Array m({py::ssize_t(3), py::ssize_t(n)}), s{py::ssize_t(n)};
    float* out = m.mutable_data();
    {
        py::gil_scoped_release nogil;
        for (size_t i = 0; i < n; ++i) {
            float d[3];
            equirect::from_uv(u.data()[i], v.data()[i], d, s.mutable_data()[i]);
            for (int a = 0; a < 3; ++a) out[size_t(a) * n + i] = d[a];
        }
    }
    return py::make_tuple(m, s);
}

// One reference to a registered IES table (dacrt.lamps.IesProfile): the table lives while a
// handle does, so whatever uses a lamp record naming .id keeps the handle (the add-on's lamps).
struct IesHandle {
    int id;
    explicit IesHandle(int i) : id(i) {}
    IesHandle(const IesHandle&) = delete;
    IesHandle& operator=(const IesHandle&) = delete;
    ~IesHandle() { ies_release(id); }
};

// Registers an IES table (addon/lights/ies.py's IESProfile): a handle whose id lamp records name.
std::unique_ptr<IesHandle> ies_register_py(F32Array h, F32Array v, F32Array intensity) {
    if (h.ndim() != 1 || v.ndim() != 1) throw py::value_error("h and v must be one-dimensional");
    need_shape(intensity, h.shape(0), size_t(v.shape(0)), "intensity");
    std::vector<float> hv(h.data(), h.data() + h.size()), vv(v.data(), v.data() + v.size()),
        iv(intensity.data(), intensity.data() + intensity.size());
    // invalid_argument: ValueError
    return std::make_unique<IesHandle>(ies_register(std::move(hv), std::move(vv), std::move(iv)));
}

// kernel_ies_interp of a profile (handle, or a live id) at each (h, v) angle pair (tests). The
// handle argument stays referenced through the call, so the table outlives the GIL-free loop.
F32Array ies_lookup_py(py::object profile, F32Array h, F32Array v) {
    const int id = py::isinstance<IesHandle>(profile) ? profile.cast<const IesHandle&>().id : profile.cast<int>();
    const IesTable* t = ies_table(id);
    if (!t) throw py::value_error("IES profile " + std::to_string(id) + " is not live (never registered, or released)");
    if (h.ndim() != 1) throw py::value_error("h must be one-dimensional, got " + shape_str(h));
    const size_t n = size_t(h.shape(0));
    need_shape(v, 0, n, "v");
    F32Array out{py::ssize_t(n)};
    float* o = out.mutable_data();
    const float *hp = h.data(), *vp = v.data();
    py::gil_scoped_release nogil;
    for (size_t i = 0; i < n; ++i) o[i] = ies_interp(*t, hp[i], vp[i]);
    return out;
}

}  // namespace

void register_lamps(py::module_& m) {
    // module_local: see LightTree below
    py::class_<IesHandle>(m, "IesProfile",
                          "A reference to a registered IES table; the table is freed when the last one goes",
                          py::module_local())
        .def_property_readonly("id", [](const IesHandle& p) { return p.id; })
        .def("__int__", [](const IesHandle& p) { return p.id; })
        .def("__index__", [](const IesHandle& p) { return p.id; })
        .def("__repr__", [](const IesHandle& p) { return "<IesProfile id " + std::to_string(p.id) + ">"; });
    m.def("ies_register", &ies_register_py, py::arg("h"), py::arg("v"), py::arg("intensity"),
          "register an IES profile table (radians, (H, V) values): an IesProfile handle, .id >= 1 for lamp records");
    m.def("ies_lookup", &ies_lookup_py, py::arg("profile"), py::arg("h"), py::arg("v"),
          "Cycles' kernel_ies_interp of a live profile (IesProfile or its id) at angle pairs");
    m.def("ies_live", &ies_live, "distinct IES tables alive now");
    m.attr("IES_MAX_TABLES") = kIesMaxTables;
    m.attr("LAMP_RECORD_WIDTH") = LAMP_RECORD_WIDTH;
    m.def("lamp_record_layout", &lamp_record_layout, "field name -> (offset, width) in float32 of a lamp record");
    m.def("lamp_sample", &lamp_sample_py, py::arg("records"), py::arg("entry"), py::arg("P"), py::arg("u1"),
          py::arg("u2"), py::arg("wi"), py::arg("dist"), py::arg("value"), py::arg("pdf"));
    m.def("lamp_gather", &lamp_gather_py, py::arg("records"), py::arg("lamps"), py::arg("lamp_prob"), py::arg("O"),
          py::arg("D"), py::arg("t_surf"), py::arg("miss"), py::arg("thr"), py::arg("pdf_bsdf"), py::arg("pid"),
          py::arg("L"), py::arg("clamp") = std::numeric_limits<float>::infinity(), py::arg("tree") = py::none(),
          py::arg("lamp_key") = py::none(), py::arg("normal") = py::none(), py::arg("receivers") = py::none());
    // module_local: the benchmark's non-robust build is loaded beside this module, and two
    // modules registering one C++ type globally fail to import ("already registered")
    py::class_<LightTree, std::shared_ptr<LightTree>>(
        m, "LightTree", "Many-light sampling: a light per point by its estimated contribution (lighttree.h)",
        py::module_local())
        .def(py::init(&make_tree), py::arg("lo"), py::arg("hi"), py::arg("axis"), py::arg("cos_o"), py::arg("cos_e"),
             py::arg("energy"), py::arg("key"), py::arg("group") = py::none(), py::arg("set") = py::none(),
             py::arg("radius") = py::none())
        .def_property_readonly("members", &LightTree::members)
        .def_property_readonly("nodes", &LightTree::nodes)
        .def("sample", &tree_sample_py, py::arg("P"), py::arg("u"), py::arg("N") = py::none(),
             py::arg("receivers") = py::none(), py::arg("rows") = false)
        .def("pdf", &tree_pdf_py, py::arg("P"), py::arg("key"), py::arg("N") = py::none(),
             py::arg("receivers") = py::none())
        .def("stop_weighs", &tree_stop_weighs_py, py::arg("P"), py::arg("N") = py::none(),
             py::arg("smallest") = false);
    m.def("next_event", &next_event_py, py::arg("records"), py::arg("cdf"), py::arg("prob"), py::arg("no_mis"),
          py::arg("shadow"), py::arg("tri_geo"), py::arg("tri_area"), py::arg("tri_emission"), py::arg("env"), py::arg("P"),
          py::arg("P_off"), py::arg("ns"), py::arg("ng"), py::arg("thr"), py::arg("keys"), py::arg("ka"), py::arg("kb"),
          py::arg("pick"), py::arg("prim"), py::arg("shorten"), py::arg("skip_work"), py::arg("value"),
          py::arg("contrib"), py::arg("rays"), py::arg("send"), py::arg("skip"), py::arg("terminator"),
          py::arg("linking") = py::none(), py::arg("entry") = py::none(), py::arg("point") = py::none(),
          py::arg("bump") = py::none(), py::arg("tree") = py::none(), py::arg("tri_prim") = py::none(),
          py::arg("rough") = py::none(), py::arg("runs") = py::none());
    m.def("choice_runs", &choice_runs_py, py::arg("cdf"));
    m.def("texel_stats", &texel_stats_py, py::arg("texels"));
    m.def("equirect_uv", &equirect_uv_py, py::arg("to_map"), py::arg("D"));
    m.def("equirect_direction", &equirect_direction_py, py::arg("u"), py::arg("v"));
    py::class_<EnvironmentMap, std::shared_ptr<EnvironmentMap>>(
        m, "EnvironmentMap", "An equirectangular environment light: radiance, pdf and samples (environment.h)",
        py::module_local())
        .def(py::init(&make_environment), py::arg("rgb"), py::arg("to_map"), py::arg("closest"),
             py::arg("srgb") = false, py::arg("scale") = py::none())
        .def_property_readonly("width", [](const EnvironmentMap& e) { return e.width; })
        .def_property_readonly("height", [](const EnvironmentMap& e) { return e.height; })
        .def_property_readonly("total", [](const EnvironmentMap& e) { return e.total; })
        .def_property_readonly("row_buckets", [](const EnvironmentMap& e) { return e.row_buckets; })
        .def_property_readonly("guide_buckets", [](const EnvironmentMap& e) { return e.guide_buckets; })
        .def("eval", &environment_eval_py, py::arg("D"))
        .def("sample", [](const EnvironmentMap& env, F32Array u1, F32Array u2) {
            return environment_sample_py(env, u1, u2, false);
        }, py::arg("u1"), py::arg("u2"))
        .def("sample_lanes", [](const EnvironmentMap& env, F32Array u1, F32Array u2) {
            return environment_sample_py(env, u1, u2, true);
        }, py::arg("u1"), py::arg("u2"))
        .def("gather", &environment_gather_py, py::arg("prob"), py::arg("D"), py::arg("miss"), py::arg("thr"),
             py::arg("pdf_bsdf"), py::arg("pid"), py::arg("L"),
             py::arg("clamp") = std::numeric_limits<float>::infinity());
    m.def("shade_bounce", &shade_bounce_py, py::arg("records"), py::arg("cdf"), py::arg("prob"), py::arg("no_mis"),
          py::arg("shadow"), py::arg("tri_geo"), py::arg("tri_area"), py::arg("tri_emission"), py::arg("env"),
          py::arg("tree"), py::arg("tri_prim"), py::arg("hits"), py::arg("hit"), py::arg("live"), py::arg("albedo"),
          py::arg("thr"), py::arg("u_rr"), py::arg("geo"), py::arg("normals"), py::arg("D"), py::arg("pid"),
          py::arg("keys"), py::arg("pick"), py::arg("nee_ka"), py::arg("nee_kb"), py::arg("shorten"),
          py::arg("skip_work"), py::arg("scatter"), py::arg("ka"), py::arg("kb"), py::arg("ray_dtype"),
          py::arg("rough") = py::none(), py::arg("geo_records") = py::none(), py::arg("runs") = py::none(),
          py::arg("draw") = py::none());
    m.def("accumulate_masked", &accumulate_masked_py, py::arg("L"), py::arg("pid"), py::arg("values"), py::arg("mask"),
          py::arg("clamp") = std::numeric_limits<float>::infinity());
}
