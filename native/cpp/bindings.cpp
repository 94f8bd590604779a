// pybind11 bindings of the native core (module dacrt._core). The public API, dtype checks and
// argument conversion live in the Python package (dacrt/__init__.py); this layer checks what it
// relies on (sizes, contiguity, finiteness, index ranges), releases the GIL while validating and
// tracing, and turns problems into ValueError / RuntimeError.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "dispatch.h"
#include "interrupt.h"
#include "parallel.h"
#include "ray_check.h"
#include "triangles.h"

namespace py = pybind11;
using namespace dacrt;

namespace {

class NativeScene {
public:
    NativeScene(py::array_t<float, py::array::c_style> vertices, py::array_t<uint32_t, py::array::c_style> triangles,
                bool keep_top, py::object masks, bool spatial_order) {
        if (keep_top) top_ = std::make_unique<TopCache>();
        if (!masks.is_none()) {
            py::array_t<uint8_t, py::array::c_style> m = masks.cast<py::array_t<uint8_t, py::array::c_style>>();
            if (m.ndim() != 1 || triangles.ndim() != 2 || m.shape(0) != triangles.shape(0))
                throw py::value_error("masks must have one entry per triangle");
            mask_.assign(m.data(), m.data() + m.shape(0));
        }
        if (vertices.ndim() != 2 || vertices.shape(1) != 3) throw py::value_error("vertices must have shape (V, 3)");
        if (triangles.ndim() != 2 || triangles.shape(1) != 3) throw py::value_error("triangles must have shape (M, 3)");
        const size_t V = size_t(vertices.shape(0)), M = size_t(triangles.shape(0));
        const float* v = vertices.data();
        const uint32_t* t = triangles.data();
        std::string err;
        {
            py::gil_scoped_release nogil;
            // Branch-free scans (they vectorise); the scalar search for the first culprit runs
            // only after one failed.
            bool finite = true;
            for (size_t i = 0; i < 3 * V; ++i) finite &= std::isfinite(v[i]);
            uint32_t most = 0;
            for (size_t i = 0; i < 3 * M; ++i) most = std::max(most, t[i]);
            for (size_t i = 0; i < 3 * V && !finite; ++i)
                if (!std::isfinite(v[i])) {
                    err = "vertices[" + std::to_string(i / 3) + "] has a non-finite coordinate (" + std::to_string(v[i]) + ")";
                    break;
                }
            for (size_t i = 0; i < 3 * M && err.empty() && most >= V; ++i)
                if (t[i] >= V)
                    err = "triangles[" + std::to_string(i / 3) + "] refers to vertex " + std::to_string(t[i]) +
                          " but there are only " + std::to_string(V) + " vertices";
            if (err.empty()) ts_ = std::make_unique<TriangleSet>(v, V, t, M, spatial_order);
        }
        if (!err.empty()) throw py::value_error(err);
    }

    size_t num_triangles() const { return ts_->boxes.size(); }
    size_t num_degenerate() const { return ts_->num_degenerate; }
    py::tuple bounds() const {
        const Bounds3& b = ts_->bounds;
        return py::make_tuple(py::make_tuple(b.lo[0], b.lo[1], b.lo[2]), py::make_tuple(b.hi[0], b.hi[1], b.hi[2]));
    }

    py::dict intersect(py::array rays, py::array hits, py::object skip, int threads, const std::string& isa,
                       int partition, int leaf_size, int leaf_rays, float sah_ratio, size_t chunk_rays, int visible,
                       py::object cancel, double poll_seconds) {
        Ray* r = check_rays(rays);
        const size_t n = size_t(rays.shape(0));
        check_out(hits, n, sizeof(Hit), "hits");
        Hit* h = static_cast<Hit*>(hits.mutable_data());
        TraceJob job{ts_.get(), config(partition, leaf_size, leaf_rays, sah_ratio, chunk_rays), Query::Closest, h, nullptr,
                     skip_ptr(skip, n), BatchInfo{}, nullptr};
        set_visible(job, visible);
        const std::unique_ptr<Interrupt> stop = interrupt(cancel, poll_seconds);
        job.interrupt = stop.get();
        return run(r, n, job, threads, isa, [&](FieldsFn f, BatchInfo& b) { return validate_rays(r, n, h, f, b, threads); });
    }

    py::dict occluded(py::array rays, py::array out, py::object skip, int threads, const std::string& isa,
                      int partition, int leaf_size, int leaf_rays, float sah_ratio, size_t chunk_rays, int visible,
                      py::object cancel, double poll_seconds) {
        Ray* r = check_rays(rays);
        const size_t n = size_t(rays.shape(0));
        check_out(out, n, 1, "occluded");
        uint8_t* o = static_cast<uint8_t*>(out.mutable_data());
        TraceJob job{ts_.get(), config(partition, leaf_size, leaf_rays, sah_ratio, chunk_rays), Query::Any, nullptr, o,
                     skip_ptr(skip, n), BatchInfo{}, nullptr};
        set_visible(job, visible);
        const std::unique_ptr<Interrupt> stop = interrupt(cancel, poll_seconds);
        job.interrupt = stop.get();
        return run(r, n, job, threads, isa, [&](FieldsFn f, BatchInfo& b) { return validate_rays(r, n, o, f, b, threads); });
    }

private:
    std::unique_ptr<TriangleSet> ts_;
    std::unique_ptr<TopCache> top_;   // null: the partition's top is rebuilt by every call
    std::vector<uint8_t> mask_;       // per triangle (empty: every triangle is seen by every call)

    // visible: bits a triangle's mask must share to be traced by this call (0: all triangles).
    void set_visible(TraceJob& job, int visible) const {
        if (visible < 0 || visible > 255) throw py::value_error("visible must be 0 (all) or 1..255");
        if (visible != 0 && !mask_.empty()) {
            job.mask = mask_.data();
            job.visible = uint8_t(visible);
        }
    }

    // The caller's cancel callable (None: none), asked with the GIL on the calling thread while
    // the trace runs without it; Python truthiness, and its exceptions propagate.
    static std::unique_ptr<Interrupt> interrupt(const py::object& cancel, double poll_seconds) {
        if (cancel.is_none()) return nullptr;
        if (!PyCallable_Check(cancel.ptr())) throw py::type_error("cancel must be a callable or None");
        if (!(poll_seconds >= 0.0)) throw py::value_error("poll_seconds must be >= 0");
        return std::make_unique<Interrupt>(
            [&cancel]() {
                py::gil_scoped_acquire gil;
                const py::object r = cancel();
                const int t = PyObject_IsTrue(r.ptr());
                if (t < 0) throw py::error_already_set();
                return t != 0;
            },
            poll_seconds);
    }

    static Config config(int partition, int leaf_size, int leaf_rays, float sah_ratio, size_t chunk_rays) {
        if (partition < 0 || partition > 2) throw py::value_error("partition must be 0 (adaptive), 1 (median) or 2 (sah)");
        if (leaf_size < 0) throw py::value_error("leaf_size must be >= 1 (0: the default, 8)");
        if (leaf_rays < 1) throw py::value_error("leaf_rays must be >= 1");
        if (!(sah_ratio >= 0.0f) || !std::isfinite(sah_ratio)) throw py::value_error("sah_ratio must be a finite number >= 0");
        Config c;
        c.partition = Partition(partition);
        c.leaf_size = leaf_size;
        c.leaf_rays = leaf_rays;
        c.sah_ratio = sah_ratio;
        c.chunk_rays = chunk_rays;
        return c;
    }
    static Ray* check_rays(py::array& rays) {
        if (rays.ndim() != 1) throw py::value_error("rays must be a 1-D array");
        if (rays.itemsize() != 32) throw py::value_error("rays must have 32-byte records (dacrt.RAY_DTYPE)");
        if (!(rays.flags() & py::array::c_style)) throw py::value_error("rays must be C-contiguous");
        if (!rays.writeable()) throw py::value_error("rays must be writeable (they are reordered in place)");
        return static_cast<Ray*>(rays.mutable_data());
    }
    // The Python layer hands a C-contiguous int32 array of n entries, or None.
    static const int32_t* skip_ptr(py::object& skip, size_t n) {
        if (skip.is_none()) return nullptr;
        py::array a = skip.cast<py::array>();
        if (a.ndim() != 1 || size_t(a.shape(0)) != n || a.itemsize() != 4 || !(a.flags() & py::array::c_style))
            throw py::value_error("internal: bad skip array");
        return static_cast<const int32_t*>(a.data());
    }
    static void check_out(py::array& a, size_t n, size_t itemsize, const char* what) {
        if (a.ndim() != 1 || size_t(a.shape(0)) != n || size_t(a.itemsize()) != itemsize ||
            !(a.flags() & py::array::c_style) || !a.writeable())
            throw py::value_error(std::string("internal: bad ") + what + " output array");
    }
    template <class Validate>
    py::dict run(Ray* r, size_t n, TraceJob& job, int threads, const std::string& isa_req, Validate validate) {
        if (threads < 0) throw py::value_error("threads must be >= 0 (0 = all cores)");
        Isa isa;
        try {
            isa = resolve_isa(isa_req);
        } catch (const std::exception& e) {
            throw std::runtime_error(e.what());
        }
        std::string err;
        TraceResult res;
        double validate_s = 0.0;
        double seconds_per_tick = 0.0;  // phase_clock() calibrated against steady_clock over this call
        {
            py::gil_scoped_release nogil;
            const auto v0 = std::chrono::steady_clock::now();
            err = validate(fields_fn(isa), job.batch);
            validate_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - v0).count();
            if (err.empty()) {
                const auto t0 = std::chrono::steady_clock::now();
                const uint64_t c0 = phase_clock();
                res = trace(*ts_, r, n, job, threads, isa, top_.get());
                const uint64_t ticks = phase_clock() - c0;
                const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                seconds_per_tick = ticks > 0 ? s / double(ticks) : 0.0;
            }
        }
        if (!err.empty()) throw py::value_error(err);
        py::dict d;
        d["rays"] = res.stats.rays;
        d["box_tests"] = res.stats.box_tests;
        d["box_hits"] = res.stats.box_hits;
        d["filter_skips"] = res.stats.filter_skips;
        d["tri_tests"] = res.stats.tri_tests;
        d["partition_steps"] = res.stats.partition_steps;
        d["steals"] = res.stats.steals;
        d["median_steps"] = res.stats.median_steps;
        d["sah_steps"] = res.stats.sah_steps;
        d["leaves"] = res.stats.leaves;
        d["double_fallbacks"] = res.stats.double_fallbacks;
        d["max_depth"] = res.stats.max_depth;
        d["threads"] = res.threads;
        d["isa"] = isa_name(isa);
        d["leaf_size"] = res.leaf_size;
        d["seconds"] = res.seconds;
        d["order_seconds"] = res.order_seconds;
        d["validate_seconds"] = validate_s;
        // Thread-seconds (summed over threads) in each phase of the recursion.
        d["filter_seconds"] = double(res.stats.filter_ticks) * seconds_per_tick;
        d["partition_seconds"] = double(res.stats.partition_ticks) * seconds_per_tick;
        d["leaf_seconds"] = double(res.stats.leaf_ticks) * seconds_per_tick;
        return d;
    }
};

}  // namespace

void register_shading(py::module_& m);  // bindings_shading.cpp
void register_lamps(py::module_& m);    // bindings_lamps.cpp
void register_images(py::module_& m);   // bindings_images.cpp

PYBIND11_MODULE(_core, m) {
    register_shading(m);
    register_lamps(m);
    register_images(m);
    m.doc() = "DACRT native core: divide-and-conquer ray tracing without acceleration structures";
    py::register_exception<Cancelled>(m, "Cancelled");
    m.def("supported_isas", &supported_isas, "ISAs this CPU can run, weakest first");
    m.def("best_isa", []() { return isa_name(resolve_isa("")); });
    m.def("check_isa", [](const std::string& s) { return isa_name(resolve_isa(s)); },
          "Resolve an ISA request ('' = best); raises RuntimeError if the CPU lacks it");
    m.def("hardware_threads", &hardware_threads);
    m.def("set_thread_limit", &set_thread_limit, py::arg("limit"),
          "Cap every native pass called from this thread (kernels, and traces given no thread count) at "
          "`limit` threads; 0: none");
    m.def("thread_limit", &thread_limit);
#ifdef DACRT_NONROBUST
    m.attr("ROBUST") = false;
#else
    m.attr("ROBUST") = true;
#endif
    py::class_<NativeScene>(m, "NativeScene", py::module_local())  // (see LightTree's)
        .def(py::init<py::array_t<float, py::array::c_style>, py::array_t<uint32_t, py::array::c_style>, bool, py::object,
                      bool>(),
             py::arg("vertices"), py::arg("triangles"), py::arg("keep_top"), py::arg("masks"), py::arg("spatial_order"))
        .def_property_readonly("num_triangles", &NativeScene::num_triangles)
        .def_property_readonly("num_degenerate", &NativeScene::num_degenerate)
        .def_property_readonly("bounds", &NativeScene::bounds)
        .def("intersect", &NativeScene::intersect)
        .def("occluded", &NativeScene::occluded);
}
