// The equirectangular mapping of many directions at once (equirect.h's to_uv and from_uv per
// lane), compiled per instruction set in envlanes.cpp: environment_gather's rays that missed and
// environment_sample_lanes' samples.
#pragma once

#include <cstddef>
#include <cstdint>

namespace dacrt {

// For j < m: the world direction (dx, dy, dz)[j] turned by to_map (row-major 3x3), its (u, v)
// and sin(theta), or sin_theta -1 where the direction has no length (zero or not finite).
void equirect_uv_lanes(const float to_map[9], const float* dx, const float* dy, const float* dz, size_t m,
                       float* u, float* v, float* sin_theta);

// What environment_sample_lanes' searches picked for up to kEnvLanes points k: the uniforms u1,
// u2, the picked row's CDF entries r0, r1 and column's c0, c1, the cell's column fj and row fi
// and, for 'Linear', its corners' luminances a (i, j), b (i, j+1), c (i+1, j), d (i+1, j+1).
constexpr size_t kEnvLanes = 128;
struct EnvPicks {
    double r0[kEnvLanes], r1[kEnvLanes];
    float u1[kEnvLanes], u2[kEnvLanes], c0[kEnvLanes], c1[kEnvLanes], fj[kEnvLanes], fi[kEnvLanes];
    float a[kEnvLanes], b[kEnvLanes], c[kEnvLanes], d[kEnvLanes];
};

// For k < m: the (u, v) environment_sample places in its picked cell of the fw x fh map
// (envcell.h: the uniforms' fractions, then 'Closest' or 'Linear').
void env_place_lanes(bool closest, float fw, float fh, const EnvPicks& in, size_t m, float* u, float* v);

// The cells between texel centres where a 'Linear' lookup at up to kEnvLanes places k reads
// (environment.cpp's cell_of): the place (fx, fy) in the cell, its rows i0, i1 = i0 + 1 and
// columns j0, j1 = j0 + 1 (wrapped), and ok where the place has a direction (sin(theta) >= 0)
// and its corners lie within one period of REPEAT (u, v in [0, 1]; elsewhere cell_of's wrap
// takes over).
struct EnvCells {
    float fx[kEnvLanes], fy[kEnvLanes];
    uint32_t i0[kEnvLanes], i1[kEnvLanes], j0[kEnvLanes], j1[kEnvLanes], ok[kEnvLanes];
};

// For k < m: the cells of a w x h map's places (u, v)[k] with sin(theta) s[k], in cell_of's
// operations (the same bits).
void env_cell_lanes(uint32_t w, uint32_t h, const float* u, const float* v, const float* s, size_t m, EnvCells& c);

// For j < m: the world direction of (u, v)[j] (from_uv, turned back by to_map's transpose) into
// wx, wy, wz and its sin(theta), in environment_sample's operations (the same bits).
void equirect_dir_lanes(const float to_map[9], const float* u, const float* v, size_t m, float* wx, float* wy,
                        float* wz, float* sin_theta);

}  // namespace dacrt
