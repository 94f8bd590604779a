// The environment map's tables (environment.h) built from an image's texels as the export holds
// them: any number of channels per texel (RGBA: alpha unread), the strength folded in while the
// texels are copied, rows spread over threads. A render at a few samples per pixel pays this
// build every frame: for a 4K HDRI the one-thread build and the numpy passes around it (the RGB
// copy, the strength's product, the checks) had cost more CPU than the 4 samples' shading.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "environment.h"

namespace dacrt {

// The environment map's tables, the same bits whatever the thread count (each row's luminance,
// CDF, guide and cell pdfs come from that row and, 'Linear', the next; the rows' totals are
// summed in row order), from texels height x width x channels (channels >= 3: the first three
// are RGB). Linear maps: each texel's RGB times scale (null: 1; float products, as numpy's
// pixels x strength) is the radiance. srgb: the RGB is sRGB-encoded and kept so, scale
// multiplying the decoded lookups (environment.h). A NaN or infinite texel channel is kept as NaN:
// every lookup blending it in reads 0 in that channel, as Cycles' film drops its NaN blend (its
// luminance for the importance reads 0). Empty string on success, else what is wrong: a finite
// texel negative or made infinite by the scale, a scale negative or not finite, the sizes, a
// to_map that is not orthogonal.
std::string build_environment_texels(EnvironmentMap& env, const float* texels, size_t channels, uint32_t width,
                                     uint32_t height, const float to_map[9], bool closest, bool srgb = false,
                                     const float* scale = nullptr);

// The same from an 8-bit image's bytes (its sRGB encoding, as Cycles keeps it): byte k is the
// texel value float32 k x 1/255, the very floats export/images.py made of them (no float copy
// of the image, 4x the bytes, is made first).
std::string build_environment_bytes(EnvironmentMap& env, const uint8_t* texels, size_t channels, uint32_t width,
                                    uint32_t height, const float to_map[9], bool closest, bool srgb = false,
                                    const float* scale = nullptr);

// What a world's map needs to know of texels n x channels (channels >= 3, RGB first): how many
// texels hold a non-finite RGB value (black: in a world map, every blend taking it in), whether a finite RGB value is negative
// (rendered 0), whether any is above 0 (the world lights anything). One threaded pass, no
// temporaries (numpy's isfinite, < 0 and > 0 over a 4K RGBA map took ~0.2 s CPU).
struct TexelStats {
    size_t non_finite = 0;
    bool negative = false, positive = false;
};
TexelStats texel_stats(const float* texels, size_t n, size_t channels);

}  // namespace dacrt
