// Image texels of 8-bit images (texels.cpp): Blender hands them to Python as floats k/255, and
// the add-on needs the bytes back (Cycles stores and blends those) and their scene-linear
// values. numpy spent one pass over the whole image per operation (an 8K texture: ~12 s and
// GBs of temporaries); here one threaded pass does what took several.
#pragma once

#include <cstddef>
#include <cstdint>

namespace dacrt {

// buf: n texels of ch (1-4) float channels; rgba: n x 4 floats, the texels as RGBA (one
// channel: grey; two: grey and alpha; no alpha: 1); k8: n x 4 bytes rint(255 rgba), clamped
// to [0, 255]; k8_assoc (or null): k8 with the colour associated with alpha as Cycles does in
// bytes, c a / 255; rgba may be null (the bytes alone: an 8-bit image kept as bytes, its floats
// made by table only if read, saves 16 bytes a texel). Returns whether every colour value is exactly byte_floats[k] (Blender's
// own float for byte k), i.e. whether a lookup by byte reproduces rgba.
bool byte_texels(const float* buf, size_t n, int ch, const float* byte_floats, float* rgba, uint8_t* k8,
                 uint8_t* k8_assoc);
// The same from the bytes themselves (an 8-bit file read as stored): rgba is byte_floats[k].
void byte_texels(const uint8_t* buf, size_t n, int ch, const float* byte_floats, float* rgba, uint8_t* k8,
                 uint8_t* k8_assoc);

// rgba[4 i + c] = table[k8[4 i + c]] for the colour channels c < 3 (alpha untouched).
void byte_lookup(const uint8_t* k8, size_t n, const float* table, float* rgba);

}  // namespace dacrt
