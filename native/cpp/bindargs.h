// Argument checks the pybind11 binding files share: shapes named in the message, triangle
// indices, output arrays written in place, and the light clamp limit.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "hitrecords.h"
#include "lighttree.h"

namespace dacrt::bindargs {

namespace py = pybind11;

inline std::string shape_str(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t k = 0; k < a.ndim(); ++k) s += (k ? ", " : "") + std::to_string(a.shape(k));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

// Checks a's shape: (rows, n) when rows > 0, else (n,).
inline void need_shape(const py::array& a, py::ssize_t rows, size_t n, const char* name) {
    const bool ok = rows > 0 ? a.ndim() == 2 && a.shape(0) == rows && size_t(a.shape(1)) == n
                             : a.ndim() == 1 && size_t(a.shape(0)) == n;
    if (!ok)
        throw py::value_error(std::string(name) + " must have shape " +
                              (rows > 0 ? "(" + std::to_string(rows) + ", " : "(") + std::to_string(n) +
                              (rows > 0 ? ")" : ",)") + ", got " + shape_str(a));
}

// Each of the n indices ix in [0, limit) (int32 triangle indices, int64 columns, ...).
template <class T>
void check_index(const T* ix, size_t n, size_t limit, const char* name) {
    for (size_t j = 0; j < n; ++j)
        if (ix[j] < 0 || size_t(ix[j]) >= limit)
            throw py::value_error(std::string(name) + "[" + std::to_string(j) + "] = " + std::to_string(ix[j]) +
                                  " is outside 0.." + std::to_string(limit ? limit - 1 : 0));
}

// A caller-provided output array the kernel writes in place.
inline float* out_array(py::array a, py::ssize_t rows, size_t n, const char* name) {
    if (!py::isinstance<py::array_t<float>>(a) || !(a.flags() & py::array::c_style) || !a.writeable())
        throw py::value_error(std::string(name) + " must be a writeable C-contiguous float32 array (written in place)");
    need_shape(a, rows, n, name);
    return static_cast<float*>(a.mutable_data());
}

// The clamp of a kernel that adds light (shading.h clamp_light): a positive limit, infinity
// for none. NaN and 0 are refused rather than read as "no light" or "no clamp".
inline void check_clamp(float clamp) {
    if (!(clamp > 0)) throw py::value_error("clamp must be > 0 (infinity: none), got " + std::to_string(clamp));
}

// The tree and the per-item keys of a gather (both or neither); keys -1 or a member's key.
inline const LightTree* tree_keys(const py::object& tree, const py::object& keys, size_t count, const char* name,
                           py::array_t<int32_t, py::array::c_style>& keep) {
    if (tree.is_none() != keys.is_none())
        throw py::value_error(std::string("tree and ") + name + " go together (both None: no light tree)");
    if (tree.is_none()) return nullptr;
    const LightTree* lt = tree.cast<const LightTree*>();
    keep = keys.cast<py::array_t<int32_t, py::array::c_style>>();
    need_shape(keep, 0, count, name);
    for (size_t k = 0; k < count; ++k)
        if (keep.data()[k] != -1 && !lt->member(keep.data()[k]))
            throw py::value_error(std::string(name) + "[" + std::to_string(k) + "] = " + std::to_string(keep.data()[k]) +
                                  " is neither -1 nor a key of the light tree");
    return lt;
}

// The hit-point records (hitrecords.h, hit_records_py) of a table of M triangles, or null for
// None; they must say whether they hold corner normals as the call does (smooth): records of
// another table shape would be read as the wrong triangles' data.
inline const float* hit_records_arg(const py::object& rec, size_t M, bool smooth,
                                    py::array_t<float, py::array::c_style>& keep) {
    if (rec.is_none()) return nullptr;
    keep = rec.cast<py::array_t<float, py::array::c_style>>();
    if (keep.ndim() != 2 || size_t(keep.shape(0)) != M || size_t(keep.shape(1)) != kHitRecord)
        throw py::value_error("records must have shape (" + std::to_string(M) + ", " + std::to_string(kHitRecord) +
                              "), got " + shape_str(keep));
    const float want = smooth ? 1.0f : 0.0f;
    if (M && (keep.data()[kRecordSmooth] != want || keep.data()[(M - 1) * kHitRecord + kRecordSmooth] != want))
        throw py::value_error(std::string("records were built ") + (smooth ? "without" : "with") +
                              " corner normals, the call has " + (smooth ? "them" : "none"));
    return keep.data();
}

}  // namespace dacrt::bindargs
