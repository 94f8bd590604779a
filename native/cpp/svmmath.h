// Cycles' SVM float helpers as Cycles writes them (util/math_base.h): max(a, b) is a > b ? a : b
// and min(a, b) is a < b ? a : b, so a NaN input clamps to the bound (clamp(NaN, 0, 1) is 0)
// where std::max / std::min would pass the NaN on and blacken the texture.
#pragma once

namespace dacrt {
namespace svm {

inline float max(float a, float b) { return a > b ? a : b; }
inline float min(float a, float b) { return a < b ? a : b; }
inline float clamp(float v, float lo, float hi) { return min(max(v, lo), hi); }

}  // namespace svm
}  // namespace dacrt
