// Image Texture lookups per point (imagepoints.cpp): texels blended at (u, v) as the add-on's
// texture._blend_texels does, and Box projection (Cycles' svm_node_tex_image_box) as
// export/procedurals._box_lookup does, in the same float32 operations in the same order, so the
// values are numpy's bit for bit (but an sRGB decode's powf: numpy's is SVML's on AVX-512,
// within an ulp). numpy made ~15 passes over the points per lookup (and a Box
// lookup three lookups plus ~20 passes for its weights): 2.4 s of a 2.5 Mpoint render.
#pragma once

#include <cstddef>
#include <cstdint>

namespace dacrt {

enum TexelInterp : int { TEXEL_CLOSEST = 0, TEXEL_LINEAR = 1, TEXEL_CUBIC = 2 };
enum TexelExtension : int { TEXEL_REPEAT = 0, TEXEL_EXTEND = 1, TEXEL_CLIP = 2, TEXEL_MIRROR = 3 };

// An image's texels (h rows, row 0 at the bottom, w columns; float32 or uint8 read as its
// value), strides in elements, and what a lookup blends: channels [c0, c1), how.
struct TexelImage {
    const void* data;
    bool bytes;
    int64_t h, w, sy, sx, sc;
    int c0, c1, interp, ext;
};

// out[k n + i], k < c1 - c0: channel c0 + k at (u[i], v[i]).
void texel_blend(const TexelImage& t, const float* u, const float* v, size_t n, float* out);

// Box projection at points co (n x 3) with object-space normals normal (n x 3): weights (n x 3)
// by _box_weights; combine: out (n x k) = sum of weight x decoded lookup over the planes whose
// weight is > 0, in plane order, decoded: times scale, then (srgb) channels 0-2 from sRGB to
// linear; else out (3 x k x n) holds each plane's raw lookup (0 where its weight is not > 0)
// for the caller to decode and weigh.
void box_lookup(const TexelImage& t, const float* co, const float* normal, size_t n, float blend, float scale,
                bool srgb, bool combine, float* weights, float* out);

}  // namespace dacrt
