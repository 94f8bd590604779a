// An equirectangular environment map as a light at infinity (Cycles' Environment Texture
// feeding the world's Background): its radiance in a direction, and directions sampled in
// proportion to it for next-event estimation (environment.cpp builds the tables).
//
// Mapping (Cycles' direction_to_equirectangular, checked against Cycles' panoramic render):
// a unit direction m in the map's frame has u = 0.5 - atan2(m.y, m.x) / 2pi and
// v = 1 - acos(m.z) / pi; texel (i, j) (row i from the bottom, the -Z pole) covers
// u in [j/w, (j+1)/w), v in [i/h, (i+1)/h). Radiance is the texture there, 'Linear' bilinear
// with texel centres at (j + 0.5)/w and REPEAT in both u and v (as Cycles: rows at a pole blend
// with the other pole's), or 'Closest', times nothing else (strength is folded into the pixels).
// An sRGB map (`srgb`: an 8-bit image, say) holds its texels in the sRGB encoding as Cycles keeps
// such an image (compress_as_srgb): the lookup blends them, decodes the blend (Cycles'
// color_srgb_to_linear) and multiplies by `scale` (the strength); its luminance below is that of
// the decoded texels.
// The world direction d reaches the map frame as m = to_map d (to_map orthogonal: the Mapping
// node's rotation and mirroring).
//
// Sampling, in proportion to the looked-up radiance's RGB mean (its luminance) x sin(theta):
// 'Closest' picks texel (i, j) by its luminance x the mean sin(theta) over its rows, then u, v
// uniform in it. 'Linear' picks a cell between texel centres (corners (i, j) .. (i+1, j+1),
// REPEAT) by its corners' mean luminance x mean sin(theta), then samples the bilinear blend of
// the corners within it exactly (pbrt-v4's bilinear sampling), so radiance / pdf is constant
// in a cell up to sin(theta) and colour (an sRGB map's decoded blend is not bilinear: there the
// ratio varies within a cell, and sampling stays unbiased). The solid-angle pdf of a direction is
// p(u, v) / (2 pi^2 sin(theta)). (Per-texel constant cells under a bilinear image left a
// one-texel sun's light spread into its neighbours to BSDF rays: 7x Cycles' noise on an HDRI
// scene; Cycles' own sampling is as good for 'Linear' as for 'Closest'.)
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "missflags.h"

namespace dacrt {

struct EnvironmentMap {
    uint32_t width = 0, height = 0;
    bool closest = false;               // 'Closest' interpolation, else bilinear
    bool srgb = false;                  // texel RGB is sRGB-encoded: decoded after the blend, then x scale
    float scale[3] = {1, 1, 1};         // multiplies an sRGB map's decoded radiance
    std::vector<float> texel;           // height x width x 4, row 0 at the bottom: RGB and luminance
                                        // (RGB mean; an sRGB map's of the decoded texel x scale)
                                        // per texel, one 16-byte record, so a corner's colour and
                                        // luminance share a cache line
    std::vector<double> row_cdf;        // height + 1: cumulative row weights / total, [0] = 0, [h] = 1
    uint32_t row_buckets = 1;           // the same guide (below) for row_cdf: R + 1 entries
    std::vector<uint32_t> row_guide;
    std::vector<float> col_cdf;         // height x (width + 1): per row, cumulative / row total
    uint32_t guide_buckets = 1;         // G, a power of two: u2 in [b/G, (b+1)/G) is bucket b
    std::vector<uint32_t> col_guide;    // height x (G + 1): per row, where u2 = b/G lands in its
                                        // CDF (std::upper_bound's position), so a sample searches
                                        // only between its bucket's two entries
    std::vector<float> cell_pdf;        // height x width: the pdf over (u, v) per cell ('Closest'), or
                                        // the factor of the corners' bilinear luminance ('Linear')
    float to_map[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};   // row-major, orthogonal
    double total = 0;                   // sum of the weights: 0 = nothing to sample
    bool steep = false;                 // a luminance above 2^60 (corners(), environment.cpp)
};

// Radiance toward world direction d (unit) and the solid-angle pdf of sampling it.
void environment_eval(const EnvironmentMap& env, const float d[3], float Le[3], float& pdf);

// A direction wi (world, unit) for uniforms u1 (row), u2 (column) in [0, 1), its radiance /
// pdf in value and its solid-angle pdf (0 and value 0 at a pole, where the map has no area).
void environment_sample(const EnvironmentMap& env, float u1, float u2, float wi[3], float value[3], float& pdf);

// environment_sample for points k < m at once (the same bits): wi and value in 3 rows of
// stride `stride`, pdf[k]. The searches and the texel loads run per point; the place in the
// cell, from_uv with the turn to the world and ('Linear' without sRGB) the pdf's and lookup's
// blends run as lane loops (envlanes.h), which one point at a time could not vectorise.
void environment_sample_lanes(const EnvironmentMap& env, const float* u1, const float* u2, size_t m, float* wi,
                              float* value, float* pdf, size_t stride);

// What rays that missed everything see of the map: L[:, pid[i]] (stride N) += thr x Le x w
// where miss(i) (missflags.h: flags or the hit records), thr null = 1, w = 1 when prob is 0 (camera rays), else the power heuristic
// 1 / (1 + (prob pdf_env / pdf_bsdf)^2). pid distinct (threads split by ray).
void environment_gather(const EnvironmentMap& env, float prob, const float* D, Missed miss,
                        const float* thr, const float* pdf_bsdf, const int64_t* pid, size_t n, float* L, size_t N,
                        float clamp);

}  // namespace dacrt
