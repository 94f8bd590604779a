// Perlin noise and its fractal sum as Cycles' Noise Texture computes them (kernel/svm/noise.h,
// fractal_noise.h, noise_texture: lookup3 hash, fBM octaves, seeded offsets for distortion and
// the colour's channels), for a renderer evaluating procedural textures at shading points.
// Float32 arithmetic in Cycles' order (the build contracts no FMA): a renderer's numpy
// reference of the same formulas gives the same bits.
#pragma once

#include <cstddef>

namespace dacrt {

// The Noise Texture (its five types: fBM and the multifractals, Offset and Gain where they read
// them) at n points p (n, dims) row-major, dims 1 to 4: W alone (1D), the Vector's x, y (2D),
// x, y, z (3D), or x, y, z and W (4D), as Cycles' svm_node_tex_noise reads them.
// Per-point parameters are arrays of length n, or of length 1 for one value for all (the
// *_n arguments give each length). fac (n,) gets the Fac output; color (n, 3) row-major, when
// not null, the Color output. Threaded.
enum NoiseType { NOISE_FBM = 0, NOISE_MULTIFRACTAL = 1, NOISE_HYBRID_MULTIFRACTAL = 2,
                 NOISE_RIDGED_MULTIFRACTAL = 3, NOISE_HETERO_TERRAIN = 4 };

struct NoiseParams {
    const float *scale, *detail, *roughness, *lacunarity, *distortion, *offset, *gain;
    size_t scale_n, detail_n, roughness_n, lacunarity_n, distortion_n, offset_n, gain_n;
    bool normalize;     // (fBM only, as Cycles)
    int type;           // NoiseType
};

void noise_texture(const float* p, size_t n, int dims, const NoiseParams& params, float* fac, float* color);

}  // namespace dacrt
