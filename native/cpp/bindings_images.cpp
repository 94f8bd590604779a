// Python bindings of the per-point image lookups (imagepoints.h).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

#include "bindargs.h"
#include "imagepoints.h"

namespace py = pybind11;
using namespace dacrt;
using namespace dacrt::bindargs;

namespace {

using F32Array = py::array_t<float, py::array::c_style>;

// The texels (h, w, c) float32 or uint8, any strides (a view reads in place: an 8-bit image's
// bytes are never copied to floats), and what is blended: channels [c0, c1), how.
TexelImage texel_image(const py::array& texels, int c0, int c1, int interp, int ext) {
    const bool bytes = py::isinstance<py::array_t<uint8_t>>(texels);
    if (!bytes && !py::isinstance<py::array_t<float>>(texels))
        throw py::value_error("texels must be a float32 or uint8 array");
    if (texels.ndim() != 3 || texels.shape(0) < 1 || texels.shape(1) < 1)
        throw py::value_error("texels must have shape (h, w, c) with h, w >= 1, got " + shape_str(texels));
    if (c0 < 0 || c1 <= c0 || c1 > texels.shape(2) || c1 - c0 > 4)
        throw py::value_error("channels [" + std::to_string(c0) + ", " + std::to_string(c1) +
                              ") must be 1 to 4 of the texels' " + std::to_string(texels.shape(2)));
    if (interp < TEXEL_CLOSEST || interp > TEXEL_CUBIC)
        throw py::value_error("interpolation must be 0..2 (Closest, Linear, Cubic)");
    if (ext < TEXEL_REPEAT || ext > TEXEL_MIRROR) throw py::value_error("extension must be 0..3 (Repeat, Extend, Clip, Mirror)");
    const py::ssize_t item = texels.itemsize();
    for (py::ssize_t k = 0; k < 3; ++k)
        if (texels.strides(k) % item) throw py::value_error("texels' strides must be whole elements");
    return {texels.data(), bytes, texels.shape(0), texels.shape(1), texels.strides(0) / item,
            texels.strides(1) / item, texels.strides(2) / item, c0, c1, interp, ext};
}

size_t points_of(const F32Array& a, py::ssize_t cols, const char* name) {
    const bool ok = cols ? a.ndim() == 2 && a.shape(1) == cols : a.ndim() == 1;
    if (!ok) throw py::value_error(std::string(name) + " must have shape " + (cols ? "(n, 3)" : "(n,)") +
                                   ", got " + shape_str(a));
    return size_t(a.shape(0));
}

F32Array texel_blend_py(py::array texels, F32Array u, F32Array v, int c0, int c1, int interp, int ext) {
    const TexelImage t = texel_image(texels, c0, c1, interp, ext);
    const size_t n = points_of(u, 0, "u");
    if (points_of(v, 0, "v") != n) throw py::value_error("u and v must have the same length");
    F32Array out({py::ssize_t(c1 - c0), py::ssize_t(n)});
    float* o = out.mutable_data();
    py::gil_scoped_release nogil;
    texel_blend(t, u.data(), v.data(), n, o);
    return out;
}

py::tuple box_lookup_py(py::array texels, F32Array co, F32Array normal, float blend, int c0, int c1, int interp,
                        int ext, float scale, bool srgb, bool combine) {
    const TexelImage t = texel_image(texels, c0, c1, interp, ext);
    const size_t n = points_of(normal, 3, "normal");
    if (points_of(co, 3, "co") != n) throw py::value_error("co and normal must have the same length");
    F32Array weights({py::ssize_t(n), py::ssize_t(3)});
    const py::ssize_t nc = c1 - c0;
    F32Array out = combine ? F32Array({py::ssize_t(n), nc}) : F32Array({py::ssize_t(3), nc, py::ssize_t(n)});
    float* w = weights.mutable_data();
    float* o = out.mutable_data();
    {
        py::gil_scoped_release nogil;
        box_lookup(t, co.data(), normal.data(), n, blend, scale, srgb, combine, w, o);
    }
    return py::make_tuple(weights, out);
}

}  // namespace

void register_images(py::module_& m) {
    m.def("texel_blend", &texel_blend_py, py::arg("texels"), py::arg("u"), py::arg("v"), py::arg("c0"), py::arg("c1"),
          py::arg("interp"), py::arg("ext"));
    m.def("box_lookup", &box_lookup_py, py::arg("texels"), py::arg("co"), py::arg("normal"), py::arg("blend"),
          py::arg("c0"), py::arg("c1"), py::arg("interp"), py::arg("ext"), py::arg("scale"), py::arg("srgb"), py::arg("combine"));
}
