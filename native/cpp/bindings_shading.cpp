// pybind11 bindings of the shading-side helper kernels (shading.h), registered into dacrt._core
// by register_shading(). Shapes and dtypes are checked here (the Python wrappers in
// dacrt/shading.py convert arguments); the GIL is released while a kernel runs.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "bindargs.h"
#include "camera.h"
#include "coplanar.h"
#include "hitrecords.h"
#include "islands.h"
#include "noise.h"
#include "orennayar.h"
#include "shading.h"
#include "texels.h"
#include "voronoi.h"

namespace py = pybind11;
using namespace dacrt;
using namespace dacrt::bindargs;

namespace {

using F32Array = py::array_t<float, py::array::c_style>;
using U32Array = py::array_t<uint32_t, py::array::c_style>;
using I64Array = py::array_t<int64_t, py::array::c_style>;

size_t rows_of(const py::array& a, py::ssize_t rows, const char* name) {
    if (a.ndim() != 2 || a.shape(0) != rows)
        throw py::value_error(std::string(name) + " must have shape (" + std::to_string(rows) + ", n)");
    return size_t(a.shape(1));
}

void need_len(const py::array& a, size_t n, const char* name) {
    if (a.ndim() != 1 || size_t(a.shape(0)) != n)
        throw py::value_error(std::string(name) + " must have shape (" + std::to_string(n) + ",)");
}

void check_index(const I64Array& idx, size_t limit, const char* name) {
    bindargs::check_index(idx.data(), size_t(idx.shape(0)), limit, name);
}

const float* optional_rows(const py::object& o, py::ssize_t rows, size_t n, const char* name, F32Array& keep) {
    if (o.is_none()) return nullptr;
    keep = o.cast<F32Array>();
    if (rows_of(keep, rows, name) != n)
        throw py::value_error(std::string(name) + " must have shape (" + std::to_string(rows) + ", " + std::to_string(n) + ")");
    return keep.data();
}

// An optional writeable (n,) uint64 output of one key per triangle (None: not wanted).
uint64_t* optional_keys(const py::object& keys, size_t n, py::array_t<uint64_t, py::array::c_style>& keep,
                        const char* name) {
    if (keys.is_none()) return nullptr;
    keep = keys.cast<py::array_t<uint64_t, py::array::c_style>>();
    if (keep.ndim() != 1 || size_t(keep.shape(0)) != n || !keep.writeable())
        throw py::value_error(std::string(name) + " must be a writeable uint64 array with one entry per triangle");
    return keep.mutable_data();
}

// A contiguous (n,) array of Record-sized records (rays or hits) to read.
template <class Record>
const Record* records(const py::array& a, size_t n, const char* what) {
    if (a.ndim() != 1 || size_t(a.shape(0)) != n || a.itemsize() != sizeof(Record) || !(a.flags() & py::array::c_style))
        throw py::value_error(std::string(what) + " must be a contiguous (" + std::to_string(n) + ",) array of " +
                              std::to_string(sizeof(Record)) + "-byte records");
    return static_cast<const Record*>(a.data());
}

// The same, to write: also writeable (a read-only array, e.g. over bytes or a read-only
// memory map, would be overwritten or fault).
template <class Record>
Record* out_records(py::array a, size_t n, const char* what) {
    records<Record>(a, n, what);
    if (!a.writeable()) throw py::value_error(std::string(what) + " must be writeable (written in place)");
    return static_cast<Record*>(a.mutable_data());
}

// An optional one-dimensional index array, each entry in [0, limit); null when absent.
const int64_t* optional_index(const py::object& o, size_t limit, const char* name, I64Array& keep) {
    if (o.is_none()) return nullptr;
    keep = o.cast<I64Array>();
    if (keep.ndim() != 1) throw py::value_error(std::string(name) + " must be one-dimensional");
    check_index(keep, limit, name);
    return keep.data();
}

void pack_rays_py(F32Array O, F32Array D, F32Array tfar, py::array out) {
    size_t n = rows_of(O, 3, "O");
    if (rows_of(D, 3, "D") != n) throw py::value_error("D must have the shape of O");
    need_len(tfar, n, "tfar");
    Ray* r = out_records<Ray>(out, n, "out");
    py::gil_scoped_release nogil;
    pack_rays(O.data(), D.data(), tfar.data(), n, r);
}

F32Array surface_py(F32Array geo, py::object normals, py::array hits, py::object idx, F32Array D,
                    py::object geo_records) {
    size_t M = rows_of(geo, 15, "geo");
    F32Array nrm_keep, rec_keep;
    const float* nrm = optional_rows(normals, 9, M, "normals", nrm_keep);
    const float* rec = hit_records_arg(geo_records, M, nrm != nullptr, rec_keep);
    size_t n = rows_of(D, 3, "D");
    const Hit* h = records<Hit>(hits, n, "hits");
    I64Array idx_keep;
    const int64_t* ix = optional_index(idx, n, "idx", idx_keep);
    const size_t k = ix ? size_t(idx_keep.shape(0)) : n;
    F32Array out({py::ssize_t(nrm ? 12 : 9), py::ssize_t(k)});
    size_t bad;
    {
        py::gil_scoped_release nogil;
        bad = surface(geo.data(), M, nrm, h, ix, k, D.data(), n, out.mutable_data(), rec);
    }
    if (bad) throw py::value_error(std::to_string(bad) + " selected hit(s) have no triangle (prim < 0 or >= " +
                                   std::to_string(M) + ")");
    return out;
}

py::tuple uniform2_py(U32Array keys, uint32_t ka, uint32_t kb) {
    size_t n = rows_of(keys, 2, "keys");
    F32Array u1{py::ssize_t(n)}, u2{py::ssize_t(n)};
    {
        py::gil_scoped_release nogil;
        uniform2_rows(keys.data(), n, ka, kb, u1.mutable_data(), u2.mutable_data());
    }
    return py::make_tuple(u1, u2);
}

py::tuple uniform_pick_py(U32Array keys, uint32_t ka, uint32_t kb) {
    size_t n = rows_of(keys, 2, "keys");
    py::array_t<double> pick{py::ssize_t(n)};
    F32Array u{py::ssize_t(n)};
    {
        py::gil_scoped_release nogil;
        uniform_pick_rows(keys.data(), n, ka, kb, pick.mutable_data(), u.mutable_data());
    }
    return py::make_tuple(pick, u);
}

py::tuple cosine_scatter_py(U32Array keys, uint32_t ka, uint32_t kb, F32Array ns, py::object ng, py::object origins,
                            py::object rays, py::object shading_offset) {
    size_t n = rows_of(keys, 2, "keys");
    if (rows_of(ns, 3, "ns") != n) throw py::value_error("ns must have shape (3, n), n = keys.shape[1]");
    F32Array ng_keep, o_keep;
    const float* g = optional_rows(ng, 3, n, "ng", ng_keep);
    const float* o = optional_rows(origins, 3, n, "origins", o_keep);
    Ray* r = nullptr;
    if (o) {
        if (rays.is_none()) throw py::value_error("origins need a rays array to fill");
        r = out_records<Ray>(rays.cast<py::array>(), n, "rays");
    }
    ShadingOffset off{};
    F32Array freq_keep;
    py::array_t<int32_t, py::array::c_style> prim_keep;
    if (!shading_offset.is_none()) {
        const py::tuple t = shading_offset.cast<py::tuple>();
        if (t.size() != 3) throw py::value_error("shading_offset is (freq, prim, thr)");
        freq_keep = t[0].cast<F32Array>();
        if (freq_keep.ndim() != 1 || freq_keep.shape(0) == 0)
            throw py::value_error("shading_offset freq must have shape (M,), M > 0, got " + shape_str(freq_keep));
        off.freq = freq_keep.data();
        off.M = size_t(freq_keep.shape(0));
        prim_keep = t[1].cast<py::array_t<int32_t, py::array::c_style>>();
        need_shape(prim_keep, 0, n, "shading_offset prim");
        bindargs::check_index(prim_keep.data(), size_t(prim_keep.shape(0)), off.M, "shading_offset prim");
        off.prim = prim_keep.data();
        off.thr = out_array(t[2].cast<py::array>(), 3, n, "shading_offset thr");
    }
    F32Array wi({py::ssize_t(3), py::ssize_t(n)}), pdf{py::ssize_t(n)};
    py::array_t<bool> ok{py::ssize_t(n)};
    {
        py::gil_scoped_release nogil;
        cosine_scatter(keys.data(), n, ka, kb, ns.data(), g, wi.mutable_data(), pdf.mutable_data(),
                       reinterpret_cast<uint8_t*>(ok.mutable_data()), o, r, off.freq ? &off : nullptr);
    }
    return py::make_tuple(wi, pdf, ok);
}

py::tuple sample_triangles_py(F32Array geo, F32Array area, I64Array which, F32Array P, F32Array u1, F32Array u2) {
    size_t M = rows_of(geo, 15, "geo");
    need_len(area, M, "area");
    size_t n = rows_of(P, 3, "P");
    need_len(which, n, "which");
    need_len(u1, n, "u1");
    need_len(u2, n, "u2");
    F32Array wi({py::ssize_t(3), py::ssize_t(n)}), target({py::ssize_t(3), py::ssize_t(n)});
    F32Array dist{py::ssize_t(n)}, pdf{py::ssize_t(n)};
    size_t bad;
    {
        py::gil_scoped_release nogil;
        bad = sample_triangles(geo.data(), area.data(), M, which.data(), P.data(), u1.data(), u2.data(), n,
                               wi.mutable_data(), dist.mutable_data(), pdf.mutable_data(), target.mutable_data());
    }
    if (bad) throw py::value_error(std::to_string(bad) + " entries of which are not triangles 0.." + std::to_string(M ? M - 1 : 0));
    return py::make_tuple(wi, dist, pdf, target);
}

F32Array rough_rows_py(F32Array params, py::array_t<int32_t, py::array::c_style> mat, F32Array rho, F32Array D,
                       F32Array ns) {
    const size_t M = rows_of(params, 4, "params"), n = rows_of(ns, 3, "ns");
    if (rows_of(rho, 3, "rho") != n || rows_of(D, 3, "D") != n)
        throw py::value_error("rho and D must have shape (3, n) like ns");
    need_len(mat, n, "mat");
    const int32_t* m = mat.data();
    for (size_t i = 0; i < n; ++i)
        if (m[i] < 0 || size_t(m[i]) >= M) throw py::value_error("mat out of range of params");
    F32Array out({py::ssize_t(kRoughRows), py::ssize_t(n)});
    {
        py::gil_scoped_release nogil;
        rough_rows(params.data(), M, m, rho.data(), D.data(), ns.data(), n, out.mutable_data());
    }
    return out;
}

void rough_scale_py(F32Array rows, F32Array wi, F32Array ns, F32Array thr) {
    const size_t n = rows_of(rows, kRoughRows, "rows");
    if (rows_of(wi, 3, "wi") != n || rows_of(ns, 3, "ns") != n || rows_of(thr, 3, "thr") != n)
        throw py::value_error("wi, ns and thr must have shape (3, n) like rows");
    py::gil_scoped_release nogil;
    rough_scale(rows.data(), wi.data(), ns.data(), n, thr.mutable_data());
}

py::array_t<bool> nee_weight_py(F32Array ns, py::object ng, F32Array wi, F32Array pdf, F32Array p_sel, py::object thr,
                                F32Array value) {
    size_t n = rows_of(ns, 3, "ns");
    if (rows_of(wi, 3, "wi") != n || rows_of(value, 3, "value") != n)
        throw py::value_error("wi and value must have shape (3, n) like ns");
    need_len(pdf, n, "pdf");
    need_len(p_sel, n, "p_sel");
    F32Array ng_keep, thr_keep;
    const float* g = optional_rows(ng, 3, n, "ng", ng_keep);
    const float* t = optional_rows(thr, 3, n, "thr", thr_keep);
    py::array_t<bool> ok{py::ssize_t(n)};
    {
        py::gil_scoped_release nogil;
        nee_weight(ns.data(), g, wi.data(), pdf.data(), p_sel.data(), t, value.mutable_data(), n,
                   reinterpret_cast<uint8_t*>(ok.mutable_data()));
    }
    return ok;
}

py::array_t<bool> shadow_rays_py(F32Array O, F32Array wi, F32Array dist, py::object target, I64Array idx, float shorten,
                                 py::array out) {
    size_t n = rows_of(O, 3, "O");
    if (rows_of(wi, 3, "wi") != n) throw py::value_error("wi must have shape (3, n) like O");
    need_len(dist, n, "dist");
    F32Array tg_keep;
    const float* tg = optional_rows(target, 3, n, "target", tg_keep);
    if (idx.ndim() != 1) throw py::value_error("idx must be one-dimensional");
    check_index(idx, n, "idx");
    size_t k = size_t(idx.shape(0));
    Ray* r = out_records<Ray>(out, k, "out");
    py::array_t<bool> valid{py::ssize_t(k)};
    {
        py::gil_scoped_release nogil;
        shadow_rays(O.data(), wi.data(), dist.data(), tg, n, idx.data(), k, shorten, r,
                    reinterpret_cast<uint8_t*>(valid.mutable_data()));
    }
    return valid;
}

py::tuple pixel_samples_py(I64Array pixel, I64Array sample, int64_t width, uint64_t k0, uint64_t k1, uint32_t ka,
                           uint32_t kb, F32Array table) {
    if (pixel.ndim() != 1) throw py::value_error("pixel must be one-dimensional");
    size_t n = size_t(pixel.shape(0));
    need_len(sample, n, "sample");
    if (width < 1) throw py::value_error("width must be >= 1");
    if (table.ndim() != 1 || table.shape(0) < 2) throw py::value_error("table must have at least 2 entries");
    const int64_t* px = pixel.data();
    const int64_t* sm = sample.data();
    for (size_t i = 0; i < n; ++i)
        if (px[i] < 0 || px[i] >= (int64_t(1) << 32) || sm[i] < 0 || sm[i] >= (int64_t(1) << 32))
            throw py::value_error("pixel and sample must be in [0, 2**32); entry " + std::to_string(i) + " is not");
    U32Array keys({py::ssize_t(2), py::ssize_t(n)});
    F32Array rx{py::ssize_t(n)}, ry{py::ssize_t(n)};
    {
        py::gil_scoped_release nogil;
        pixel_samples(px, sm, n, width, k0, k1, ka, kb, table.data(), size_t(table.shape(0)), keys.mutable_data(),
                      rx.mutable_data(), ry.mutable_data());
    }
    return py::make_tuple(keys, rx, ry);
}

py::tuple block_samples_py(I64Array pixels, int64_t s0, int64_t ns, int64_t width, uint64_t k0, uint64_t k1,
                           uint32_t ka, uint32_t kb, F32Array table) {
    if (pixels.ndim() != 1) throw py::value_error("pixels must be one-dimensional");
    const size_t npix = size_t(pixels.shape(0));
    if (width < 1) throw py::value_error("width must be >= 1");
    if (ns < 1) throw py::value_error("ns must be >= 1");
    if (s0 < 0 || s0 + ns > (int64_t(1) << 32)) throw py::value_error("samples s0 .. s0 + ns - 1 must be in [0, 2**32)");
    if (table.ndim() != 1 || table.shape(0) < 2) throw py::value_error("table must have at least 2 entries");
    const int64_t* px = pixels.data();
    for (size_t i = 0; i < npix; ++i)
        if (px[i] < 0 || px[i] >= (int64_t(1) << 32))
            throw py::value_error("pixels must be in [0, 2**32); entry " + std::to_string(i) + " is not");
    const size_t n = npix * size_t(ns);
    U32Array keys({py::ssize_t(2), py::ssize_t(n)});
    F32Array rx{py::ssize_t(n)}, ry{py::ssize_t(n)};
    {
        py::gil_scoped_release nogil;
        block_samples(px, npix, s0, size_t(ns), width, k0, k1, ka, kb, table.data(), size_t(table.shape(0)),
                      keys.mutable_data(), rx.mutable_data(), ry.mutable_data());
    }
    return py::make_tuple(keys, rx, ry);
}

// The Columns of `arrays` (each C-contiguous (n,) or (rows, n), the same n) taken at k
// indices, with their fresh outputs appended to out; n: their column count (0 when none).
std::vector<Columns> columns_of(const py::list& arrays, size_t k, py::list& out, size_t& n) {
    std::vector<Columns> cols;
    n = 0;
    for (size_t a = 0; a < arrays.size(); ++a) {
        py::array src = arrays[a].cast<py::array>();
        const std::string name = "arrays[" + std::to_string(a) + "]";
        if ((src.ndim() != 1 && src.ndim() != 2) || !(src.flags() & py::array::c_style))
            throw py::value_error(name + " must be a C-contiguous (n,) or (rows, n) array");
        const size_t itemsize = size_t(src.itemsize());
        if (itemsize != 1 && itemsize != 2 && itemsize != 4 && itemsize != 8)
            throw py::value_error(name + " has " + std::to_string(itemsize) + "-byte elements (1, 2, 4 or 8 supported)");
        const size_t cols_n = size_t(src.shape(src.ndim() - 1)), rows = src.ndim() == 2 ? size_t(src.shape(0)) : 1;
        if (a == 0) n = cols_n;
        else if (cols_n != n) throw py::value_error(name + " has " + std::to_string(cols_n) + " columns, arrays[0] " +
                                                    std::to_string(n));
        std::vector<py::ssize_t> shape;
        if (src.ndim() == 2) shape.push_back(py::ssize_t(rows));
        shape.push_back(py::ssize_t(k));
        py::array dst(src.dtype(), shape);
        cols.push_back({src.data(), dst.mutable_data(), rows, n, itemsize});
        out.append(dst);
    }
    return cols;
}

py::tuple continue_paths_py(py::array hits, py::array_t<bool, py::array::c_style> hit,
                            py::array_t<bool, py::array::c_style> live, F32Array albedo, py::object thr,
                            py::object u_rr, py::object geo, py::object normals, py::object D, py::list take,
                            py::object geo_records) {
    const size_t n = hits.ndim() == 1 ? size_t(hits.shape(0)) : 0;
    const Hit* h = records<Hit>(hits, n, "hits");
    need_len(hit, n, "hit");
    if (live.ndim() != 1) throw py::value_error("live must be one-dimensional");
    size_t M = size_t(live.shape(0));
    if (rows_of(albedo, 3, "albedo") != M) throw py::value_error("albedo must have shape (3, M), M = len(live)");
    F32Array thr_keep, rr_keep, geo_keep, nrm_keep, D_keep;
    const float* t = optional_rows(thr, 3, n, "thr", thr_keep);
    const float* r = nullptr;
    if (!u_rr.is_none()) {
        rr_keep = u_rr.cast<F32Array>();
        need_len(rr_keep, n, "u_rr");
        r = rr_keep.data();
    }
    // the survivors' surface points (geo given) and columns (take) in the same pass
    const float* g = optional_rows(geo, 15, M, "geo", geo_keep);
    const float* nrm = g ? optional_rows(normals, 9, M, "normals", nrm_keep) : nullptr;
    const float* d = g ? optional_rows(D, 3, n, "D", D_keep) : nullptr;
    if (g && !d) throw py::value_error("geo needs D, the rays' directions");
    F32Array rec_keep;
    const float* rec = g ? hit_records_arg(geo_records, M, nrm != nullptr, rec_keep) : nullptr;
    I64Array idx{py::ssize_t(n)};
    size_t k, black, rr;
    {
        py::gil_scoped_release nogil;
        k = survivors(h, reinterpret_cast<const uint8_t*>(hit.data()), n, reinterpret_cast<const uint8_t*>(live.data()),
                      M, t, r, idx.mutable_data(), &black, &rr);
    }
    idx.resize({py::ssize_t(k)});
    F32Array thr_out({py::ssize_t(3), py::ssize_t(k)});
    py::object surf = py::none(), prim = py::none();
    float* surf_out = nullptr;
    int32_t* prim_out = nullptr;
    if (g) {
        F32Array so({py::ssize_t(nrm ? 12 : 9), py::ssize_t(k)});
        py::array_t<int32_t> po{py::ssize_t(k)};
        surf_out = so.mutable_data();
        prim_out = po.mutable_data();
        surf = so;
        prim = po;
    }
    py::list taken;
    size_t tn = 0;
    const std::vector<Columns> cols = columns_of(take, k, taken, tn);
    if (!cols.empty() && tn != n)
        throw py::value_error("take: arrays have " + std::to_string(tn) + " columns, hits " + std::to_string(n));
    {
        py::gil_scoped_release nogil;
        survivor_throughput(h, n, albedo.data(), M, t, r != nullptr, idx.data(), k, thr_out.mutable_data(), g, nrm, d,
                            surf_out, prim_out, rec);
        if (!cols.empty()) take_columns(cols.data(), cols.size(), idx.data(), k);
    }
    return py::make_tuple(idx, thr_out, black, rr, surf, prim, taken);
}

size_t gather_emission_py(py::array hits, py::object hit, F32Array emission,
                          py::array_t<bool, py::array::c_style> emissive, py::object tri_prob, F32Array area,
                          F32Array geo, F32Array O, F32Array D, py::object thr, py::object pdf, I64Array pid,
                          py::array_t<float, py::array::c_style> L, float clamp, py::object tree,
                          py::object tri_key, py::object normal, py::object receivers) {
    check_clamp(clamp);
    const size_t n = hits.ndim() == 1 ? size_t(hits.shape(0)) : 0;
    const Hit* h = records<Hit>(hits, n, "hits");
    // hit None: every ray, those of prim < 0 left out as a missed one is (the caller makes no
    // flags from the records)
    py::array_t<bool, py::array::c_style> hit_keep;
    if (!hit.is_none()) {
        hit_keep = hit.cast<py::array_t<bool, py::array::c_style>>();
        need_len(hit_keep, n, "hit");
    }
    const size_t M = rows_of(geo, 15, "geo");
    if (rows_of(emission, 3, "emission") != M) throw py::value_error("emission must have shape (3, M) like geo");
    need_len(emissive, M, "emissive");
    need_len(area, M, "area");
    if (rows_of(O, 3, "O") != n) throw py::value_error("O must have shape (3, n), n = len(hits)");
    if (rows_of(D, 3, "D") != n) throw py::value_error("D must have shape (3, n), n = len(hits)");
    F32Array thr_keep, prob_keep, pdf_keep;
    const float* t = optional_rows(thr, 3, n, "thr", thr_keep);
    const float* prob = nullptr;
    const float* pd = nullptr;
    if (!tri_prob.is_none()) {
        if (pdf.is_none()) throw py::value_error("pdf (the BSDF pdf of each ray) is needed with tri_prob");
        prob_keep = tri_prob.cast<F32Array>();
        need_len(prob_keep, M, "tri_prob");
        pdf_keep = pdf.cast<F32Array>();
        need_len(pdf_keep, n, "pdf");
        prob = prob_keep.data();
        pd = pdf_keep.data();
    }
    need_len(pid, n, "pid");
    if (!L.writeable()) throw py::value_error("L must be writeable");
    const size_t N = rows_of(L, 3, "L");
    check_index(pid, N, "pid");
    py::array_t<int32_t, py::array::c_style> key_keep;
    const LightTree* lt = tree_keys(tree, tri_key, M, "tri_key", key_keep);
    F32Array normal_keep;
    const float* nv = optional_rows(normal, 3, n, "normal", normal_keep);
    py::array_t<uint64_t, py::array::c_style> recv_keep;
    if (!receivers.is_none()) {
        recv_keep = receivers.cast<py::array_t<uint64_t, py::array::c_style>>();
        need_len(recv_keep, n, "receivers");
    }
    const uint64_t* recv = receivers.is_none() ? nullptr : recv_keep.data();
    py::gil_scoped_release nogil;
    return gather_emission(h, hit.is_none() ? nullptr : reinterpret_cast<const uint8_t*>(hit_keep.data()), n,
                           emission.data(),
                           reinterpret_cast<const uint8_t*>(emissive.data()), prob, area.data(), geo.data(), M,
                           O.data(), D.data(), t, pd, pid.data(), L.mutable_data(), N, clamp, lt,
                           lt ? key_keep.data() : nullptr, nv, recv);
}

py::tuple camera_rays_py(bool ortho, F32Array frame, F32Array rx, F32Array ry, py::object rays, py::object lu_obj,
                         py::object lv_obj, bool sheared) {
    if (frame.ndim() != 1 || frame.shape(0) != 27)
        throw py::value_error("frame must hold 27 floats (rotation 9, position 3, ortho base 3, raster map 4, "
                              "tan_half_fov, clip_start, clip_range, aperture, focal_distance, blades, "
                              "blade_rotation, inv_ratio)");
    const float* f = frame.data();
    CameraFrame c{};
    c.ortho = ortho;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) c.rot[a][b] = f[3 * a + b];
    for (int a = 0; a < 3; ++a) c.pos[a] = f[9 + a], c.ortho_base[a] = f[12 + a];
    c.sx0 = f[15], c.sx_scale = f[16], c.sy0 = f[17], c.sy_scale = f[18];
    c.tan_half_fov = f[19], c.clip_start = f[20], c.clip_range = f[21];
    c.aperture = f[22], c.focal_distance = f[23], c.blades = f[24], c.blade_rotation = f[25], c.inv_ratio = f[26];
    for (int k = 22; k < 27; ++k)
        if (!std::isfinite(f[k])) throw py::value_error("frame's depth of field values must be finite");
    if (c.aperture < 0.0f || (c.aperture > 0.0f && !(c.focal_distance > 0.0f && c.inv_ratio > 0.0f)))
        throw py::value_error("depth of field needs aperture >= 0 and, with an aperture, a positive focal "
                              "distance and inverse ratio");
    if (rx.ndim() != 1) throw py::value_error("rx must be one-dimensional");
    const size_t n = size_t(rx.shape(0));
    need_len(ry, n, "ry");
    if (lu_obj.is_none() != lv_obj.is_none()) throw py::value_error("lu and lv are given together");
    F32Array lu, lv;
    if (!lu_obj.is_none()) {
        lu = lu_obj.cast<F32Array>();
        lv = lv_obj.cast<F32Array>();
        need_len(lu, n, "lu");
        need_len(lv, n, "lv");
    }
    F32Array O({py::ssize_t(3), py::ssize_t(n)}), D({py::ssize_t(3), py::ssize_t(n)}), tmax{py::ssize_t(n)};
    Ray* rec = rays.is_none() ? nullptr : out_records<Ray>(rays.cast<py::array>(), n, "rays");
    {
        py::gil_scoped_release nogil;
        (sheared ? sheared_camera_rays : camera_rays)(c, rx.data(), ry.data(), n, O.mutable_data(), D.mutable_data(),
                                                      tmax.mutable_data(), rec, lu_obj.is_none() ? nullptr : lu.data(),
                                                      lv_obj.is_none() ? nullptr : lv.data());
    }
    return py::make_tuple(O, D, tmax);
}

py::array_t<double> sample_sums_py(F32Array values, py::object weights) {
    if (values.ndim() < 1) throw py::value_error("values must have at least one dimension (samples last)");
    const size_t S = size_t(values.shape(values.ndim() - 1));
    py::array_t<double> out(std::vector<py::ssize_t>(values.shape(), values.shape() + values.ndim() - 1));
    py::array_t<double, py::array::c_style | py::array::forcecast> w;
    if (!weights.is_none()) {
        w = weights.cast<py::array_t<double, py::array::c_style | py::array::forcecast>>();
        need_len(w, S, "weights");
    }
    const double* wp = weights.is_none() ? nullptr : w.data();
    py::gil_scoped_release nogil;
    sample_sums(values.data(), size_t(out.size()), S, wp, out.mutable_data());  // no samples: sums of 0
    return out;
}

py::list take_columns_py(I64Array idx, py::list arrays) {
    if (idx.ndim() != 1) throw py::value_error("idx must be one-dimensional");
    const size_t k = size_t(idx.shape(0));
    py::list out;
    size_t n = 0;
    const std::vector<Columns> cols = columns_of(arrays, k, out, n);
    if (!cols.empty()) check_index(idx, n, "idx");
    {
        py::gil_scoped_release nogil;
        take_columns(cols.data(), cols.size(), idx.data(), k);
    }
    return out;
}

// drop_columns in place (shading.h): arrays C-contiguous, writeable, (n,) or (rows, n), none
// sharing bytes with another; rays (n,) records or None. Returns m.
size_t drop_columns_py(py::array_t<bool, py::array::c_style> keep, py::list arrays, py::object rays) {
    if (keep.ndim() != 1) throw py::value_error("keep must be one-dimensional");
    const size_t n = size_t(keep.shape(0));
    std::vector<Columns> cols;
    std::vector<std::pair<const char*, const char*>> spans;
    for (size_t a = 0; a < arrays.size(); ++a) {
        py::array x = arrays[a].cast<py::array>();
        const std::string name = "arrays[" + std::to_string(a) + "]";
        if ((x.ndim() != 1 && x.ndim() != 2) || !(x.flags() & py::array::c_style) || !x.writeable())
            throw py::value_error(name + " must be a writeable C-contiguous (n,) or (rows, n) array");
        const size_t itemsize = size_t(x.itemsize()), rows = x.ndim() == 2 ? size_t(x.shape(0)) : 1;
        if (size_t(x.shape(x.ndim() - 1)) != n)
            throw py::value_error(name + " has " + std::to_string(x.shape(x.ndim() - 1)) + " columns, keep " +
                                  std::to_string(n));
        cols.push_back({x.data(), x.mutable_data(), rows, n, itemsize});
        spans.emplace_back(static_cast<const char*>(x.data()), static_cast<const char*>(x.data()) + rows * n * itemsize);
    }
    Ray* r = rays.is_none() ? nullptr : out_records<Ray>(rays.cast<py::array>(), n, "rays");
    if (r) spans.emplace_back(reinterpret_cast<const char*>(r), reinterpret_cast<const char*>(r + n));
    for (size_t a = 0; a < spans.size(); ++a)
        for (size_t b = a + 1; b < spans.size(); ++b)
            if (spans[a].first < spans[b].second && spans[b].first < spans[a].second)
                throw py::value_error("the arrays must not share memory (each is compacted in place)");
    py::gil_scoped_release nogil;
    return drop_columns(reinterpret_cast<const uint8_t*>(keep.data()), n, cols.data(), cols.size(), r);
}

// Shapes of a mesh's (V, 3) vertices and (M, 3) triangles, every index checked: (V, M).
std::pair<size_t, size_t> mesh_sizes(const py::array& vertices, const py::array_t<int32_t, py::array::c_style>& triangles) {
    if (vertices.ndim() != 2 || vertices.shape(1) != 3) throw py::value_error("vertices must have shape (V, 3)");
    if (triangles.ndim() != 2 || triangles.shape(1) != 3) throw py::value_error("triangles must have shape (M, 3)");
    const size_t V = size_t(vertices.shape(0)), M = size_t(triangles.shape(0));
    const int32_t* t = triangles.data();
    // (the largest index as unsigned, a negative one past every V, in a loop that vectorises;
    // the first bad one looked for only when there is one: one branch a corner had cost ~1.5 ms
    // per 1M triangles, twice a frame)
    uint32_t top = 0;
    for (size_t i = 0; i < 3 * M; ++i) top = std::max(top, uint32_t(t[i]));
    if (M && size_t(top) >= V)
        for (size_t i = 0; i < 3 * M; ++i)
            if (t[i] < 0 || size_t(t[i]) >= V)
                throw py::value_error("triangles[" + std::to_string(i / 3) + "] refers to vertex " +
                                      std::to_string(t[i]) + " but there are " + std::to_string(V) + " vertices");
    return {V, M};
}

void transform_points_py(F32Array points, py::array_t<double, py::array::c_style> linear, py::object offset,
                         py::array out) {
    if (points.ndim() != 2 || points.shape(1) != 3) throw py::value_error("points must have shape (n, 3), got " + shape_str(points));
    if (linear.ndim() != 3 || linear.shape(1) != 3 || linear.shape(2) != 3)
        throw py::value_error("linear must have shape (k, 3, 3), got " + shape_str(linear));
    const size_t n = size_t(points.shape(0)), k = size_t(linear.shape(0));
    py::array_t<double, py::array::c_style> off;
    if (!offset.is_none()) {
        off = py::array_t<double, py::array::c_style>::ensure(offset);
        if (!off || off.ndim() != 2 || size_t(off.shape(0)) != k || off.shape(1) != 3)
            throw py::value_error("offset must be None or have shape (k, 3)");
    }
    const bool f32 = py::isinstance<py::array_t<float>>(out), f64 = py::isinstance<py::array_t<double>>(out);
    if (!(f32 || f64) || !(out.flags() & py::array::c_style) || !out.writeable() || out.ndim() != 3 ||
        size_t(out.shape(0)) != k || size_t(out.shape(1)) != n || out.shape(2) != 3)
        throw py::value_error("out must be a writeable C-contiguous float32 or float64 array of shape (" +
                              std::to_string(k) + ", " + std::to_string(n) + ", 3), got " + shape_str(out));
    const double* o = offset.is_none() ? nullptr : off.data();
    void* dst = out.mutable_data();
    py::gil_scoped_release nogil;
    if (f32) transform_points(points.data(), n, linear.data(), o, k, static_cast<float*>(dst));
    else transform_points(points.data(), n, linear.data(), o, k, static_cast<double*>(dst));
}

py::tuple face_normals_py(py::array_t<double, py::array::c_style> vertices,
                          py::array_t<int32_t, py::array::c_style> triangles) {
    const auto [V, M] = mesh_sizes(vertices, triangles);
    const int32_t* t = triangles.data();
    F32Array normals({py::ssize_t(M), py::ssize_t(3)});
    py::array_t<bool> good{py::ssize_t(M)};
    {
        py::gil_scoped_release nogil;
        face_normals(vertices.data(), V, t, M, normals.mutable_data(), reinterpret_cast<uint8_t*>(good.mutable_data()));
    }
    return py::make_tuple(normals, good);
}

py::array_t<int64_t> island_roots_py(size_t V, py::array_t<int32_t, py::array::c_style | py::array::forcecast> edges) {
    if (edges.ndim() != 2 || edges.shape(1) != 2)
        throw py::value_error("edges must have shape (m, 2), got " + shape_str(edges));
    const size_t m = size_t(edges.shape(0));
    const int32_t* e = edges.data();
    for (size_t k = 0; k < 2 * m; ++k)
        if (e[k] < 0 || size_t(e[k]) >= V)
            throw py::value_error("edge " + std::to_string(k / 2) + " has vertex " + std::to_string(e[k]) +
                                  ", outside 0.." + std::to_string(V) + "-1");
    py::array_t<int64_t> roots{py::ssize_t(V)};
    {
        py::gil_scoped_release nogil;
        island_roots(V, e, m, roots.mutable_data());
    }
    return roots;
}

bool normals_flat_py(F32Array normals, F32Array geo, float tol) {
    const size_t M = rows_of(geo, 15, "geo");
    if (normals.ndim() != 3 || size_t(normals.shape(0)) != M || normals.shape(1) != 3 || normals.shape(2) != 3)
        throw py::value_error("normals must have shape (M, 3, 3), M = geo.shape[1]");
    py::gil_scoped_release nogil;
    return normals_flat(normals.data(), geo.data(), M, tol);
}

F32Array corner_rows_py(F32Array per_corner) {
    if (per_corner.ndim() != 3 || per_corner.shape(1) != 3 || per_corner.shape(2) < 1)
        throw py::value_error("per_corner must have shape (M, 3, c) with c >= 1");
    const size_t M = size_t(per_corner.shape(0)), c = size_t(per_corner.shape(2));
    F32Array rows({py::ssize_t(3 * c), py::ssize_t(M)});
    py::gil_scoped_release nogil;
    corner_rows(per_corner.data(), M, c, rows.mutable_data());
    return rows;
}

py::array_t<bool> repeated_keys_py(py::array_t<uint64_t, py::array::c_style | py::array::forcecast> keys) {
    if (keys.ndim() != 1) throw py::value_error("keys must be one-dimensional");
    const size_t n = size_t(keys.shape(0));
    py::array_t<bool> out{py::ssize_t(n)};
    {
        py::gil_scoped_release nogil;
        repeated_keys(keys.data(), n, reinterpret_cast<uint8_t*>(out.mutable_data()));
    }
    return out;
}

py::tuple coplanar_groups_py(py::array_t<uint64_t, py::array::c_style> keys, F32Array geo,
                             py::array_t<int32_t, py::array::c_style> triangles,
                             py::array_t<uint8_t, py::array::c_style | py::array::forcecast> candidates,
                             size_t max_group) {
    const size_t M = rows_of(geo, 15, "geo");
    if (triangles.ndim() != 2 || size_t(triangles.shape(0)) != M || triangles.shape(1) != 3)
        throw py::value_error("triangles must have shape (M, 3), one row per column of geo");
    need_len(keys, M, "keys");
    need_len(candidates, M, "candidates");
    if (M >= (size_t(1) << 31)) throw py::value_error("at most 2^31 - 1 triangles");
    std::vector<int64_t> rows, start;
    {
        py::gil_scoped_release nogil;
        coplanar_groups(keys.data(), geo.data(), M, triangles.data(), candidates.data(), max_group, rows, start);
    }
    I64Array r{py::ssize_t(rows.size())}, s{py::ssize_t(start.size())};
    std::copy(rows.begin(), rows.end(), r.mutable_data());
    std::copy(start.begin(), start.end(), s.mutable_data());
    return py::make_tuple(r, s);
}

// The overlap check's second key grid (coplanar.h).
py::array_t<uint64_t, py::array::c_style> shifted_plane_keys_py(
    F32Array geo, py::array_t<uint8_t, py::array::c_style | py::array::forcecast> candidates, float inv_step) {
    const size_t M = rows_of(geo, 15, "geo");
    need_len(candidates, M, "candidates");
    py::array_t<uint64_t, py::array::c_style> out{py::ssize_t(M)};
    {
        py::gil_scoped_release nogil;
        shifted_plane_keys(geo.data(), M, candidates.data(), inv_step, out.mutable_data());
    }
    return out;
}

// The hit-point records of a table (hitrecords.h): (M, 32) float32, each record on its own
// two cache lines: a view, 128-byte aligned, into a numpy array 32 floats longer (numpy aligns
// to 16 bytes; its allocator reuses a frame's freed blocks, where an aligned_alloc of its own
// faulted in fresh pages every frame).
F32Array hit_records_py(F32Array geo, py::object normals) {
    const size_t M = rows_of(geo, 15, "geo");
    F32Array nrm_keep;
    const float* nrm = optional_rows(normals, 9, M, "normals", nrm_keep);
    F32Array block{py::ssize_t(M * kHitRecord + 32)};
    float* mem = block.mutable_data();
    mem += (128 - reinterpret_cast<uintptr_t>(mem) % 128) % 128 / sizeof(float);
    {
        py::gil_scoped_release nogil;
        hit_records(geo.data(), M, nrm, mem);
    }
    return F32Array({py::ssize_t(M), py::ssize_t(kHitRecord)}, mem, block);
}

py::tuple triangle_table_py(F32Array vertices, py::array_t<int32_t, py::array::c_style> triangles, float offset_ulps,
                            float tiny, py::object full, py::object keys, py::object plane_keys, float plane_inv_step) {
    const auto [V, M] = mesh_sizes(vertices, triangles);
    const int32_t* t = triangles.data();
    py::array_t<uint8_t, py::array::c_style | py::array::forcecast> flags;
    if (!full.is_none()) {
        flags = full.cast<py::array_t<uint8_t, py::array::c_style | py::array::forcecast>>();
        if (flags.ndim() != 1 || size_t(flags.shape(0)) != M)
            throw py::value_error("full must hold one entry per triangle");
    }
    const uint8_t* f = full.is_none() ? nullptr : flags.data();
    py::array_t<uint64_t, py::array::c_style> key_out;
    uint64_t* k = optional_keys(keys, M, key_out, "keys");
    py::array_t<uint64_t, py::array::c_style> plane_out;
    uint64_t* pk = optional_keys(plane_keys, M, plane_out, "plane_keys");
    F32Array geo({py::ssize_t(15), py::ssize_t(M)});
    py::array_t<double> area{py::ssize_t(M)};
    {
        py::gil_scoped_release nogil;
        triangle_table(vertices.data(), V, t, M, offset_ulps, tiny, f, geo.mutable_data(), area.mutable_data(), k, pk,
                       plane_inv_step);
    }
    return py::make_tuple(geo, area);
}

// A Noise Texture parameter: n values or one for all.
size_t param_len(const F32Array& a, size_t n, const char* name) {
    if (a.ndim() != 1 || (size_t(a.shape(0)) != n && a.shape(0) != 1))
        throw py::value_error(std::string(name) + " must have shape (" + std::to_string(n) + ",) or (1,), got " +
                              shape_str(a));
    return size_t(a.shape(0));
}

py::tuple noise_texture_py(F32Array points, F32Array scale, F32Array detail, F32Array roughness,
                           F32Array lacunarity, F32Array distortion, bool normalize, bool color, int type,
                           F32Array offset, F32Array gain) {
    if (points.ndim() != 2 || points.shape(1) < 1 || points.shape(1) > 4)
        throw py::value_error("points must have shape (n, 1..4), got " + shape_str(points));
    const int dims = int(points.shape(1));
    if (type < NOISE_FBM || type > NOISE_HETERO_TERRAIN)
        throw py::value_error("type must be 0..4 (fBM, multifractal, hybrid, ridged, hetero terrain), got " +
                              std::to_string(type));
    const size_t n = size_t(points.shape(0));
    NoiseParams k{scale.data(), detail.data(), roughness.data(), lacunarity.data(), distortion.data(), offset.data(),
                  gain.data(), param_len(scale, n, "scale"), param_len(detail, n, "detail"),
                  param_len(roughness, n, "roughness"), param_len(lacunarity, n, "lacunarity"),
                  param_len(distortion, n, "distortion"), param_len(offset, n, "offset"), param_len(gain, n, "gain"),
                  normalize, type};
    F32Array fac{py::ssize_t(n)};
    py::object col = py::none();
    float* c = nullptr;
    if (color) {
        F32Array rgb({py::ssize_t(n), py::ssize_t(3)});
        c = rgb.mutable_data();
        col = rgb;
    }
    {
        py::gil_scoped_release nogil;
        noise_texture(points.data(), n, dims, k, fac.mutable_data(), c);
    }
    return py::make_tuple(fac, col);
}

py::tuple voronoi_texture_py(F32Array points, F32Array scale, F32Array detail, F32Array roughness,
                             F32Array lacunarity, F32Array smoothness, F32Array exponent, F32Array randomness,
                             int feature, int metric, bool normalize) {
    if (points.ndim() != 2 || points.shape(1) < 1 || points.shape(1) > 4)
        throw py::value_error("points must have shape (n, 1..4), got " + shape_str(points));
    const int dims = int(points.shape(1));
    if (metric < VORONOI_EUCLIDEAN || metric > VORONOI_MINKOWSKI)
        throw py::value_error("metric must be 0..3 (Euclidean, Manhattan, Chebychev, Minkowski), got " +
                              std::to_string(metric));
    if (feature < VORONOI_F1 || feature > VORONOI_N_SPHERE_RADIUS)
        throw py::value_error("feature must be 0..4 (F1, F2, Smooth F1, Distance to Edge, N-Sphere Radius), got " +
                              std::to_string(feature));
    const size_t n = size_t(points.shape(0));
    VoronoiTextureParams k{scale.data(), detail.data(), roughness.data(), lacunarity.data(), smoothness.data(),
                           exponent.data(), randomness.data(), param_len(scale, n, "scale"),
                           param_len(detail, n, "detail"), param_len(roughness, n, "roughness"),
                           param_len(lacunarity, n, "lacunarity"), param_len(smoothness, n, "smoothness"),
                           param_len(exponent, n, "exponent"), param_len(randomness, n, "randomness"),
                           feature, metric, normalize};
    F32Array dist{py::ssize_t(n)}, radius{py::ssize_t(n)};
    F32Array color({py::ssize_t(n), py::ssize_t(3)}), position({py::ssize_t(n), py::ssize_t(4)});
    {
        py::gil_scoped_release nogil;
        voronoi_texture(points.data(), n, dims, k, dist.mutable_data(), color.mutable_data(),
                        position.mutable_data(), radius.mutable_data());
    }
    return py::make_tuple(dist, color, position, radius);
}

// The leading shape of an image array (..., c) and its texel count; c must be in [lo, hi].
std::pair<std::vector<py::ssize_t>, size_t> texel_shape(const py::array& a, py::ssize_t lo, py::ssize_t hi,
                                                        const char* name) {
    if (a.ndim() < 1 || a.shape(a.ndim() - 1) < lo || a.shape(a.ndim() - 1) > hi)
        throw py::value_error(std::string(name) + " must have shape (..., c) with " + std::to_string(lo) +
                              " <= c <= " + std::to_string(hi));
    std::vector<py::ssize_t> lead(a.shape(), a.shape() + a.ndim() - 1);
    size_t n = 1;
    for (py::ssize_t d : lead) n *= size_t(d);
    return {lead, n};
}

const float* byte_table(const F32Array& table, const char* name) {
    if (table.ndim() != 1 || table.shape(0) != 256) throw py::value_error(std::string(name) + " must have shape (256,)");
    return table.data();
}

py::tuple byte_texels_py(py::array buf, F32Array byte_floats, bool associate, bool floats) {
    const bool bytes = py::isinstance<py::array_t<uint8_t>>(buf);
    if (!bytes && !py::isinstance<py::array_t<float>>(buf))
        throw py::value_error("buf must be a float32 or uint8 array");
    if (!(buf.flags() & py::array::c_style)) throw py::value_error("buf must be C-contiguous");
    auto [lead, n] = texel_shape(buf, 1, 4, "buf");
    const float* bf = byte_table(byte_floats, "byte_floats");
    std::vector<py::ssize_t> shape = lead;
    shape.push_back(4);
    // floats false: no RGBA (None), the bytes alone (16 bytes a texel saved: 1 GB an 8K image)
    F32Array rgba(floats ? shape : std::vector<py::ssize_t>{0});
    float* out = floats ? rgba.mutable_data() : nullptr;
    py::array_t<uint8_t> k8(shape);
    py::object assoc = py::none();
    uint8_t* ka = nullptr;
    if (associate) {
        py::array_t<uint8_t> a(shape);
        ka = a.mutable_data();
        assoc = a;
    }
    const int ch = int(buf.shape(buf.ndim() - 1));
    bool exact = true;
    {
        py::gil_scoped_release nogil;
        if (bytes)
            byte_texels(static_cast<const uint8_t*>(buf.data()), n, ch, bf, out, k8.mutable_data(), ka);
        else
            exact = byte_texels(static_cast<const float*>(buf.data()), n, ch, bf, out,
                                k8.mutable_data(), ka);
    }
    return py::make_tuple(floats ? py::object(rgba) : py::none(), k8, assoc, exact);
}

void byte_lookup_py(py::array_t<uint8_t, py::array::c_style> k8, F32Array table, py::array rgba) {
    auto [lead, n] = texel_shape(k8, 4, 4, "k8");
    const float* t = byte_table(table, "table");
    auto [lead_out, n_out] = texel_shape(rgba, 4, 4, "rgba");
    if (lead_out != lead) throw py::value_error("rgba must have k8's shape");
    if (!py::isinstance<py::array_t<float>>(rgba) || !(rgba.flags() & py::array::c_style) || !rgba.writeable())
        throw py::value_error("rgba must be a writeable C-contiguous float32 array (written in place)");
    float* out = static_cast<float*>(rgba.mutable_data());
    py::gil_scoped_release nogil;
    byte_lookup(k8.data(), n, t, out);
}

}  // namespace

void register_shading(py::module_& m) {
    m.def("pack_rays", &pack_rays_py, py::arg("O"), py::arg("D"), py::arg("tfar"), py::arg("out"));
    m.def("repeated_keys", &repeated_keys_py, py::arg("keys"));
    m.def("coplanar_groups", &coplanar_groups_py, py::arg("keys"), py::arg("geo"), py::arg("triangles"),
          py::arg("candidates"), py::arg("max_group"));
    m.def("shifted_plane_keys", &shifted_plane_keys_py, py::arg("geo"), py::arg("candidates"), py::arg("inv_step"));
    m.def("triangle_table", &triangle_table_py, py::arg("vertices"), py::arg("triangles"), py::arg("offset_ulps"),
          py::arg("tiny"), py::arg("full") = py::none(), py::arg("keys") = py::none(),
          py::arg("plane_keys") = py::none(), py::arg("plane_inv_step") = 0.0f);
    m.def("surface", &surface_py, py::arg("geo"), py::arg("normals"), py::arg("hits"), py::arg("idx"), py::arg("D"),
          py::arg("records") = py::none());
    m.def("hit_records", &hit_records_py, py::arg("geo"), py::arg("normals"));
    m.def("uniform2", &uniform2_py, py::arg("keys"), py::arg("ka"), py::arg("kb"));
    m.def("uniform_pick", &uniform_pick_py, py::arg("keys"), py::arg("ka"), py::arg("kb"));
    m.def("cosine_scatter", &cosine_scatter_py, py::arg("keys"), py::arg("ka"), py::arg("kb"), py::arg("ns"),
          py::arg("ng"), py::arg("origins"), py::arg("rays"), py::arg("shading_offset") = py::none());
    m.def("sample_triangles", &sample_triangles_py, py::arg("geo"), py::arg("area"), py::arg("which"), py::arg("P"),
          py::arg("u1"), py::arg("u2"));
    m.def("rough_rows", &rough_rows_py, py::arg("params"), py::arg("mat"), py::arg("rho"), py::arg("D"), py::arg("ns"));
    m.def("rough_scale", &rough_scale_py, py::arg("rows"), py::arg("wi"), py::arg("ns"), py::arg("thr"));
    m.def("nee_weight", &nee_weight_py, py::arg("ns"), py::arg("ng"), py::arg("wi"), py::arg("pdf"), py::arg("p_sel"),
          py::arg("thr"), py::arg("value"));
    m.def("shadow_rays", &shadow_rays_py, py::arg("O"), py::arg("wi"), py::arg("dist"), py::arg("target"), py::arg("idx"),
          py::arg("shorten"), py::arg("out"));
    m.def("pixel_samples", &pixel_samples_py, py::arg("pixel"), py::arg("sample"), py::arg("width"), py::arg("k0"),
          py::arg("k1"), py::arg("ka"), py::arg("kb"), py::arg("table"));
    m.def("block_samples", &block_samples_py, py::arg("pixels"), py::arg("s0"), py::arg("ns"), py::arg("width"),
          py::arg("k0"), py::arg("k1"), py::arg("ka"), py::arg("kb"), py::arg("table"));
    m.def("continue_paths", &continue_paths_py, py::arg("hits"), py::arg("hit"), py::arg("live"), py::arg("albedo"),
          py::arg("thr"), py::arg("u_rr"), py::arg("geo") = py::none(), py::arg("normals") = py::none(),
          py::arg("D") = py::none(), py::arg("take") = py::list(), py::arg("records") = py::none());
    m.def("gather_emission", &gather_emission_py, py::arg("hits"), py::arg("hit"), py::arg("emission"),
          py::arg("emissive"), py::arg("tri_prob"), py::arg("area"), py::arg("geo"), py::arg("O"), py::arg("D"),
          py::arg("thr"), py::arg("pdf"), py::arg("pid"), py::arg("L"),
          py::arg("clamp") = std::numeric_limits<float>::infinity(), py::arg("tree") = py::none(),
          py::arg("tri_key") = py::none(), py::arg("normal") = py::none(), py::arg("receivers") = py::none());
    m.def("camera_rays", &camera_rays_py, py::arg("ortho"), py::arg("frame"), py::arg("rx"), py::arg("ry"),
          py::arg("rays"), py::arg("lu") = py::none(), py::arg("lv") = py::none(), py::arg("sheared") = false);
    m.def("take_columns", &take_columns_py, py::arg("idx"), py::arg("arrays"));
    m.def("drop_columns", &drop_columns_py, py::arg("keep"), py::arg("arrays"), py::arg("rays"));
    m.def("sample_sums", &sample_sums_py, py::arg("values"), py::arg("weights"));
    m.def("face_normals", &face_normals_py, py::arg("vertices"), py::arg("triangles"));
    m.def("transform_points", &transform_points_py, py::arg("points"), py::arg("linear"), py::arg("offset"),
          py::arg("out"));
    m.def("corner_rows", &corner_rows_py, py::arg("per_corner"));
    m.def("island_roots", &island_roots_py, py::arg("vertex_count"), py::arg("edges"));
    m.def("normals_flat", &normals_flat_py, py::arg("normals"), py::arg("geo"), py::arg("tol"));
    m.def("noise_texture", &noise_texture_py, py::arg("points"), py::arg("scale"), py::arg("detail"),
          py::arg("roughness"), py::arg("lacunarity"), py::arg("distortion"), py::arg("normalize"), py::arg("color"),
          py::arg("type"), py::arg("offset"), py::arg("gain"));
    m.def("byte_texels", &byte_texels_py, py::arg("buf"), py::arg("byte_floats"), py::arg("associate"),
          py::arg("floats") = true);
    m.def("byte_lookup", &byte_lookup_py, py::arg("k8"), py::arg("table"), py::arg("rgba"));
    m.def("voronoi_texture", &voronoi_texture_py, py::arg("points"), py::arg("scale"), py::arg("detail"),
          py::arg("roughness"), py::arg("lacunarity"), py::arg("smoothness"), py::arg("exponent"),
          py::arg("randomness"), py::arg("feature"), py::arg("metric"), py::arg("normalize"));
}
