// camera_rays' pinhole lane loop (cameralanes.h). One ray at a time the loop ran three
// divisions and a square root per ray in scalar registers, with the ortho and lens branches
// in between (1.8% of a Cornell render's CPU); here each step runs for every lane. The
// operations and their order are the scalar loop's (and -ffp-contract=off: no clone fuses a
// multiply-add), so every clone gives the same bits.
#include "cameralanes.h"

#include <cmath>

namespace dacrt {

__attribute__((target_clones("avx512f", "avx2", "default")))
void pinhole_lanes(const CameraFrame& c, const float* __restrict rx, const float* __restrict ry, size_t b, size_t e,
                   size_t n, float* __restrict O, float* __restrict D, float* __restrict tmax) {
    const float sx0 = c.sx0, sxs = c.sx_scale, sy0 = c.sy0, sys = c.sy_scale, tf = c.tan_half_fov;
    const float cs = c.clip_start, cr = c.clip_range;
    float r[3][3], pos[3];
    for (int a = 0; a < 3; ++a) {
        pos[a] = c.pos[a];
        for (int k = 0; k < 3; ++k) r[a][k] = c.rot[a][k];
    }
    float* __restrict Ox = O;
    float* __restrict Oy = O + n;
    float* __restrict Oz = O + 2 * n;
    float* __restrict Dx = D;
    float* __restrict Dy = D + n;
    float* __restrict Dz = D + 2 * n;
    for (size_t i = b; i < e; ++i) {
        float sx = sx0 + rx[i] * sxs, sy = sy0 + ry[i] * sys;
        sx *= tf;
        sy *= tf;
        const float inv_len = 1.0f / std::sqrt(sx * sx + sy * sy + 1.0f);
        const float start = cs / inv_len;
        tmax[i] = cr / inv_len;
        const float dx = (r[0][0] * sx + r[0][1] * sy - r[0][2]) * inv_len;
        const float dy = (r[1][0] * sx + r[1][1] * sy - r[1][2]) * inv_len;
        const float dz = (r[2][0] * sx + r[2][1] * sy - r[2][2]) * inv_len;
        Dx[i] = dx;
        Dy[i] = dy;
        Dz[i] = dz;
        Ox[i] = dx * start + pos[0];
        Oy[i] = dy * start + pos[1];
        Oz[i] = dz * start + pos[2];
    }
}

}  // namespace dacrt
