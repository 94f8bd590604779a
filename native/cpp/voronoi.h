// The Voronoi Texture's F1 feature as Cycles computes it (kernel/svm/voronoi.h): the nearest of
// the points jittered into the integer cells around a point (PCG-hashed cells), its distance,
// its cell's colour and its position; float32 in Cycles' order, for a renderer evaluating
// procedural textures at shading points.
#pragma once

#include <cstddef>

namespace dacrt {

enum VoronoiMetric { VORONOI_EUCLIDEAN = 0, VORONOI_MANHATTAN = 1, VORONOI_CHEBYCHEV = 2 };

// At n points p (n, dims) row-major, dims 2 or 3, already scaled (Cycles' coord x Scale), with
// randomness per point (length n) or one for all (length 1): distance (n,), color (n, 3) and
// position (n, 3) row-major (the nearest point in the same scaled space; z 0 in 2D). Threaded.
void voronoi_f1(const float* p, size_t n, int dims, const float* randomness, size_t randomness_n, int metric,
                float* distance, float* color, float* position);

}  // namespace dacrt
