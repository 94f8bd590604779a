// Camera rays for raster positions (see shading.h): the pinhole and orthographic mappings of
// addon/camera.py (Cycles' camera), one threaded pass instead of a dozen numpy passes.
#include <cmath>

#include "parallel.h"
#include "pathvertex.h"
#include "shading.h"

namespace dacrt {

void camera_rays(const CameraFrame& c, const float* rx, const float* ry, size_t n, float* O, float* D,
                 float* tmax, Ray* rays) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            float sx = c.sx0 + rx[i] * c.sx_scale, sy = c.sy0 + ry[i] * c.sy_scale;
            if (c.ortho) {
                // origin on the clip-start plane, offset across the view; one direction for all
                for (int a = 0; a < 3; ++a) {
                    O[size_t(a) * n + i] = c.rot[a][0] * sx + c.rot[a][1] * sy + c.ortho_base[a];
                    D[size_t(a) * n + i] = -c.rot[a][2];
                }
                tmax[i] = c.clip_range;
                if (rays) ray_record(O, D, n, i, tmax[i], rays[i]);
                continue;
            }
            sx *= c.tan_half_fov;
            sy *= c.tan_half_fov;
            const float inv_len = 1.0f / std::sqrt(sx * sx + sy * sy + 1.0f);   // d_cam.z
            // world direction R (sx, sy, -1) / |.| (R orthonormal); a plane at depth z is z / d_cam.z away
            const float start = c.clip_start / inv_len;
            for (int a = 0; a < 3; ++a) {
                const float d = (c.rot[a][0] * sx + c.rot[a][1] * sy - c.rot[a][2]) * inv_len;
                D[size_t(a) * n + i] = d;
                O[size_t(a) * n + i] = d * start + c.pos[a];
            }
            tmax[i] = c.clip_range / inv_len;
            if (rays) ray_record(O, D, n, i, tmax[i], rays[i]);
        }
    }, size_t(1) << 16);
}

}  // namespace dacrt
