// The light tree's AVX-512 lane copies (treelanes.h): a stop's eight lanes at one point in a
// 256-bit vector, and a lane at rows of points sixteen at a time (the rows are padded to 16).
// Compiled with the AVX-512 flags (CMakeLists.txt, as kernel_avx512.cpp), in its own namespace.
// Measured (a standalone build of sample_rows on many_lights' tree, 200K points, the same bits):
// eight points a step 83-86 ns a point, sixteen 75-79.
#include <cstddef>
#include <cstdint>

#include "treelanes.h"

#pragma GCC diagnostic ignored "-Wpsabi"

namespace dacrt {
namespace avx512 {
namespace {
#include "treeweigh.h"
}  // namespace

DACRT_TREE_ISA(tree, , W8, WM8, W16, WM16)

}  // namespace avx512
}  // namespace dacrt
