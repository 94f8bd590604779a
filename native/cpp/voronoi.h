// The Voronoi Texture as Cycles computes it (kernel/svm/voronoi.h): the nearest of the points
// jittered into the integer cells around a point (PCG-hashed cells; 1D: lookup3 of the cell's
// float), its distance, its cell's colour and its position, for the whole node (voronoi_texture:
// every feature, metric and dimension, and the fractal octaves); float32 in Cycles' order, for a
// renderer evaluating procedural textures at shading points.
#pragma once

#include <cstddef>

namespace dacrt {

enum VoronoiMetric { VORONOI_EUCLIDEAN = 0, VORONOI_MANHATTAN = 1, VORONOI_CHEBYCHEV = 2, VORONOI_MINKOWSKI = 3 };
enum VoronoiFeature { VORONOI_F1 = 0, VORONOI_F2 = 1, VORONOI_SMOOTH_F1 = 2, VORONOI_DISTANCE_TO_EDGE = 3,
                      VORONOI_N_SPHERE_RADIUS = 4 };

// The Voronoi Texture node (Cycles' svm_node_tex_voronoi) at n points p (n, dims) row-major,
// dims 1 (W), 2 (x, y), 3 (x, y, z) or 4 (x, y, z, W), unscaled. Per-point parameters are arrays
// of length n or 1 (the *_n fields). Outputs: distance (n,), color (n, 3), position (n, 4) (x, y,
// z, W as Cycles' float4: 1D's coordinate in W), radius (n,) (N-Sphere Radius); each feature
// writes what Cycles writes, zeros elsewhere. Threaded.
struct VoronoiTextureParams {
    const float *scale, *detail, *roughness, *lacunarity, *smoothness, *exponent, *randomness;
    size_t scale_n, detail_n, roughness_n, lacunarity_n, smoothness_n, exponent_n, randomness_n;
    int feature;        // VoronoiFeature
    int metric;         // VoronoiMetric (1D reads none: the distance is |a - b|)
    bool normalize;
};

void voronoi_texture(const float* p, size_t n, int dims, const VoronoiTextureParams& params, float* distance,
                     float* color, float* position, float* radius);

}  // namespace dacrt
