// Camera rays for raster positions (see shading.h): the pinhole and orthographic mappings of
// addon/camera.py (Cycles' camera) and Cycles' thin-lens depth of field, one threaded pass
// instead of a dozen numpy passes.
#include <cmath>

#include "camera.h"
#include "cameralanes.h"
#include "parallel.h"
#include "pathvertex.h"
#include "raylanes.h"
#include "shading.h"

namespace dacrt {

namespace {

// A point of the unit aperture for uniforms (u, v): the unit disk (concentric mapping, as
// Cycles' sample_uniform_disk) or, with blades >= 3, the regular polygon inscribed in it
// (Cycles' regular_polygon_sample), rotated; x then scaled by inv_ratio.
void aperture_point(const CameraFrame& c, float u, float v, float& x, float& y) {
    constexpr float kPi = 3.14159265358979f;
    if (c.blades < 3.0f) {
        const float a = 2.0f * u - 1.0f, b = 2.0f * v - 1.0f;
        float r, theta;
        if (a == 0.0f && b == 0.0f) {
            r = 0.0f, theta = 0.0f;
        } else if (std::fabs(a) > std::fabs(b)) {
            r = a, theta = 0.25f * kPi * (b / a);
        } else {
            r = b, theta = 0.5f * kPi - 0.25f * kPi * (a / b);
        }
        x = r * std::cos(theta);
        y = r * std::sin(theta);
    } else {
        // a corner's triangle (centre, two neighbouring corners on the unit circle), uniform
        const float corner = std::floor(u * c.blades);
        float s = std::sqrt(u * c.blades - corner), t = v * s;
        s = 1.0f - s;
        const float half = kPi / c.blades;
        const float px = (s + t) * std::cos(half), py = (s - t) * std::sin(half);
        const float rot = c.blade_rotation + corner * 2.0f * kPi / c.blades;
        const float cr = std::cos(rot), sr = std::sin(rot);
        x = cr * px - sr * py;
        y = sr * px + cr * py;
    }
    x *= c.inv_ratio;
}

// Scales the world direction w to unit length and writes it as ray i's direction (a sheared
// camera's: Cycles' normalize(transform_direction(cameratoworld, D))).
inline void unit_direction(const float w[3], float* D, size_t n, size_t i, float d[3]) {
    const float inv = 1.0f / std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    for (int a = 0; a < 3; ++a) D[size_t(a) * n + i] = d[a] = w[a] * inv;
}

// The one-ray-at-a-time mapping: orthographic, depth of field, and every sheared camera.
void scalar_rays(const CameraFrame& c, const float* rx, const float* ry, size_t n, float* O, float* D,
                 float* tmax, Ray* rays, const float* lu, const float* lv, bool lens, bool sheared) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            float sx = c.sx0 + rx[i] * c.sx_scale, sy = c.sy0 + ry[i] * c.sy_scale;
            float lx = 0.0f, ly = 0.0f;  // lens point (camera space)
            if (lens) {
                aperture_point(c, lu[i], lv[i], lx, ly);
                lx *= c.aperture;
                ly *= c.aperture;
            }
            if (c.ortho) {
                // origin on the clip-start plane, offset across the view; one direction for all
                tmax[i] = c.clip_range;
                if (!lens) {
                    for (int a = 0; a < 3; ++a) {
                        O[size_t(a) * n + i] = c.rot[a][0] * sx + c.rot[a][1] * sy + c.ortho_base[a];
                        D[size_t(a) * n + i] = -c.rot[a][2];
                    }
                    if (rays) ray_record(O, D, n, i, tmax[i], rays[i]);
                    continue;
                }
                // with a lens: from the lens point on the camera plane towards the pinhole ray's
                // point at the focus distance from the camera plane (measured against Cycles: not
                // from the clip-start plane), starting where it crosses the clip-start plane
                const float len = std::sqrt(lx * lx + ly * ly + c.focal_distance * c.focal_distance);
                const float inv = 1.0f / len, start = c.clip_start * len / c.focal_distance;
                const float dc[3] = {-lx * inv, -ly * inv, -c.focal_distance * inv};
                float w[3], unit[3];
                for (int a = 0; a < 3; ++a) {
                    const float d = c.rot[a][0] * dc[0] + c.rot[a][1] * dc[1] + c.rot[a][2] * dc[2];
                    w[a] = d;
                    D[size_t(a) * n + i] = d;
                    O[size_t(a) * n + i] = c.rot[a][0] * (sx + lx) + c.rot[a][1] * (sy + ly) + c.pos[a] + d * start;
                }
                // sheared: the origin is the camera-space point mapped by the matrix, as above; only
                // the direction is scaled to unit length, and clip_range is measured along it
                if (sheared) unit_direction(w, D, n, i, unit);
                if (rays) ray_record(O, D, n, i, tmax[i], rays[i]);
                continue;
            }
            sx *= c.tan_half_fov;
            sy *= c.tan_half_fov;
            const float inv_len = 1.0f / std::sqrt(sx * sx + sy * sy + 1.0f);   // d_cam.z
            // world direction R (sx, sy, -1) / |.| (R orthonormal); a plane at depth z is z / d_cam.z away
            // (Cycles clips along the lens ray by the pinhole ray's factor too)
            const float start = c.clip_start / inv_len;
            tmax[i] = c.clip_range / inv_len;
            if (sheared) {
                // Cycles' camera_sample_perspective: the world direction normalised after the
                // matrix, the clip distances (camera-space depth / d_cam.z) laid along it, from the
                // pinhole or the lens point mapped by the matrix; not the sheared image of the plane
                float w[3], d[3], lens_w[3] = {0.0f, 0.0f, 0.0f};
                if (!lens) {
                    for (int a = 0; a < 3; ++a) w[a] = c.rot[a][0] * sx + c.rot[a][1] * sy - c.rot[a][2];
                } else {
                    const float fx = sx * c.focal_distance - lx, fy = sy * c.focal_distance - ly,
                                fz = -c.focal_distance;
                    for (int a = 0; a < 3; ++a) {
                        w[a] = c.rot[a][0] * fx + c.rot[a][1] * fy + c.rot[a][2] * fz;
                        lens_w[a] = c.rot[a][0] * lx + c.rot[a][1] * ly;
                    }
                }
                unit_direction(w, D, n, i, d);
                for (int a = 0; a < 3; ++a) O[size_t(a) * n + i] = lens_w[a] + c.pos[a] + d[a] * start;
            } else if (!lens) {
                for (int a = 0; a < 3; ++a) {
                    const float d = (c.rot[a][0] * sx + c.rot[a][1] * sy - c.rot[a][2]) * inv_len;
                    D[size_t(a) * n + i] = d;
                    O[size_t(a) * n + i] = d * start + c.pos[a];
                }
            } else {
                // the pinhole ray meets the plane of focus at (sx, sy, -1) * focal_distance
                const float fx = sx * c.focal_distance - lx, fy = sy * c.focal_distance - ly, fz = -c.focal_distance;
                const float inv = 1.0f / std::sqrt(fx * fx + fy * fy + fz * fz);
                for (int a = 0; a < 3; ++a) {
                    const float d = (c.rot[a][0] * fx + c.rot[a][1] * fy + c.rot[a][2] * fz) * inv;
                    D[size_t(a) * n + i] = d;
                    O[size_t(a) * n + i] = c.rot[a][0] * lx + c.rot[a][1] * ly + c.pos[a] + d * start;
                }
            }
            if (rays) ray_record(O, D, n, i, tmax[i], rays[i]);
        }
    }, size_t(1) << 16);
}

}  // namespace

void camera_rays(const CameraFrame& c, const float* rx, const float* ry, size_t n, float* O, float* D,
                 float* tmax, Ray* rays, const float* lu, const float* lv) {
    const bool lens = c.aperture > 0.0f && lu && lv;
    if (!c.ortho && !lens) {  // the common camera: its lane loop, then the records
        parallel_for(n, [&](size_t b, size_t e) {
            pinhole_lanes(c, rx, ry, b, e, n, O, D, tmax);
            if (rays) ray_records_lanes(O, D, n, b, e, tmax, 0.0f, rays);
        }, size_t(1) << 16);
        return;
    }
    scalar_rays(c, rx, ry, n, O, D, tmax, rays, lu, lv, lens, false);
}

void sheared_camera_rays(const CameraFrame& c, const float* rx, const float* ry, size_t n, float* O, float* D,
                         float* tmax, Ray* rays, const float* lu, const float* lv) {
    scalar_rays(c, rx, ry, n, O, D, tmax, rays, lu, lv, c.aperture > 0.0f && lu && lv, true);
}

}  // namespace dacrt
