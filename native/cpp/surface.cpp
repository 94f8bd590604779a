// Hit-point reconstruction for shading (see shading.h): the same arithmetic, in the same order,
// as the numpy code it replaces, one pass per ray instead of one per operation.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <vector>

#include "coplanar.h"
#include "hitrecords.h"
#include "parallel.h"
#include "pathvertex.h"
#include "shading.h"
#include "triangles.h"

namespace dacrt {

namespace {
constexpr uint64_t kCornerMix[3] = {0x9E3779B97F4A7C15ull, 0xC2B2AE3D27D4EB4Full, 0x165667B19E3779F9ull};
}  // namespace

// Radix-partitioned: the keys (with their entries) go to buckets by their top hash bits,
// ~4K keys a bucket, and each bucket finds its repeats in an open-addressing table of its own
// that stays in cache. One table over all keys had missed the cache on every probe once it
// outgrew it: 65 ns a key at 1.25M keys (2M triangles, 67 ms a frame), 5 ns at 100K.
void repeated_keys(const uint64_t* keys, size_t n, uint8_t* out) {
    std::memset(out, 0, n);
    auto mixed = [](uint64_t k) { return k * 0x9E3779B97F4A7C15ull; };  // (the key's own bits are a hash)
    size_t live = 0;
    for (size_t i = 0; i < n; ++i) live += keys[i] != 0;
    int bits = 0;
    while (bits < 16 && (live >> bits) > 4096) ++bits;
    const size_t buckets = size_t(1) << bits;
    std::vector<size_t> start(buckets + 1, 0);
    auto bucket_of = [&](uint64_t k) { return bits ? size_t(mixed(k) >> (64 - bits)) : size_t(0); };
    for (size_t i = 0; i < n; ++i)
        if (keys[i]) ++start[bucket_of(keys[i]) + 1];
    for (size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
    std::vector<uint64_t> key(live);
    std::vector<uint32_t> entry(live);
    {
        std::vector<size_t> fill(start.begin(), start.end() - 1);
        for (size_t i = 0; i < n; ++i) {
            const uint64_t k = keys[i];
            if (!k) continue;
            const size_t at = fill[bucket_of(k)]++;
            key[at] = k;
            entry[at] = uint32_t(i);
        }
    }
    parallel_for(buckets, [&](size_t b0, size_t b1) {
        std::vector<uint64_t> slot;
        std::vector<uint32_t> first;
        for (size_t b = b0; b < b1; ++b) {
            const size_t lo = start[b], m = start[b + 1] - lo;
            size_t cap = 16;
            while (cap < 2 * m) cap <<= 1;
            const size_t mask = cap - 1;
            slot.assign(cap, 0);  // 0: empty (keys of 0 are never stored)
            first.resize(cap);    // the entry that filled the slot
            for (size_t j = lo; j < lo + m; ++j) {
                const uint64_t k = key[j];
                size_t h = size_t(mixed(k) >> 17) & mask;
                while (slot[h] != 0 && slot[h] != k) h = (h + 1) & mask;
                if (slot[h] == 0) {
                    slot[h] = k;
                    first[h] = entry[j];
                } else {
                    out[entry[j]] = 1;
                    out[first[h]] = 1;
                }
            }
        }
    }, 8);
}

void triangle_table(const float* vertices, size_t V, const int32_t* triangles, size_t M, float offset_ulps, float tiny,
                    const uint8_t* full, float* geo, double* area, uint64_t* keys, uint64_t* plane_keys,
                    float plane_inv_step) {
    // In blocks of kBlock triangles, two loops each: the corners gathered, differenced, hashed
    // and the cross product kept; then, with no gathers, the square roots, divisions and steps
    // (a loop whose iterations overlap, and vectorise: in one loop per triangle the chain of
    // sqrt and three divisions had stalled each triangle), and the plane keys from the rows
    // just written (in cache). The same operations in the same order: the same bits.
    constexpr size_t kBlock = 256;
    parallel_for(M, [&](size_t b, size_t e) {
        double nb[3][kBlock];
        float axb[3][kBlock], magb[kBlock];
        uint8_t fb[kBlock];
        for (size_t b0 = b; b0 < e; b0 += kBlock) {
            const size_t n = std::min(e, b0 + kBlock) - b0;
            for (size_t j = 0; j < n; ++j) {
                const size_t i = b0 + j;
                const float* c[3];
                for (int k = 0; k < 3; ++k) c[k] = vertex_of(vertices, V, triangles, 3 * i + size_t(k));
                double e1[3], e2[3];
                float mag = tiny;
                for (int a = 0; a < 3; ++a) {
                    e1[a] = double(c[1][a]) - double(c[0][a]);
                    e2[a] = double(c[2][a]) - double(c[0][a]);
                    float axis = tiny;
                    for (int k = 0; k < 3; ++k) axis = std::max(axis, std::fabs(c[k][a]));
                    mag = std::max(mag, axis);
                    axb[a][j] = axis;
                    geo[size_t(a) * M + i] = c[0][a];
                    geo[size_t(3 + a) * M + i] = float(e1[a]);
                    geo[size_t(6 + a) * M + i] = float(e2[a]);
                }
                nb[0][j] = e1[1] * e2[2] - e1[2] * e2[1];
                nb[1][j] = e1[2] * e2[0] - e1[0] * e2[2];
                nb[2][j] = e1[0] * e2[1] - e1[1] * e2[0];
                magb[j] = mag;
                fb[j] = full ? full[i] : 0;
                if (keys) {
                    // an order-free hash of the corners' bits (+0: -0 as 0), every triangle: twins
                    // to step off (where the step shrank) and exact copies to say
                    // (coincidentfaces.py, which compares the candidates bit for bit). Linear in
                    // the bits, but no key of 1.4M grid triangles (both diagonals, flat and wavy,
                    // in one binade and across zero) repeated another's
                    uint64_t key = 0;
                    for (int k = 0; k < 3; ++k) {
                        uint64_t h = 0;
                        for (int a = 0; a < 3; ++a) {
                            const float x = c[k][a] + 0.0f;
                            uint32_t bits;
                            std::memcpy(&bits, &x, 4);
                            h += uint64_t(bits) * kCornerMix[a];
                        }
                        key += h;
                    }
                    keys[i] = key | 1;  // never 0 (0: no key, repeated_keys skips it)
                }
            }
            for (size_t j = 0; j < n; ++j) {
                const size_t i = b0 + j;
                const double n0 = nb[0][j], n1 = nb[1][j], n2 = nb[2][j];
                const double len = std::sqrt(n0 * n0 + n1 * n1 + n2 * n2);
                area[i] = 0.5 * len;
                // (divided by 1 where the area is 0: the same values where they are used, and no
                // division by 0 computed, so the loop has no branch)
                const bool ok = len > 0;
                const double by = ok ? len : 1.0;
                const double u0 = n0 / by, u1 = n1 / by, u2 = n2 / by;
                // along the normal only P's error there (see shading.h): sum_a |n_a| ulp(axis_a)
                // of the ULPs of the largest coordinate, all of it for a triangle with a twin
                double sum = 0.0;
                sum += std::fabs(u0) * ulp_of(axb[0][j]);
                sum += std::fabs(u1) * ulp_of(axb[1][j]);
                sum += std::fabs(u2) * ulp_of(axb[2][j]);
                const float ulp = ulp_of(magb[j]);
                const float share = !fb[j] && ok ? float(std::min(1.0, sum / ulp)) : 1.0f;
                const float step = ulp * offset_ulps * share;
                const float g0 = ok ? float(u0) : 0.0f, g1 = ok ? float(u1) : 0.0f, g2 = ok ? float(u2) : 0.0f;
                geo[9 * M + i] = g0;
                geo[10 * M + i] = g1;
                geo[11 * M + i] = g2;
                geo[12 * M + i] = g0 * step;
                geo[13 * M + i] = g1 * step;
                geo[14 * M + i] = g2 * step;
            }
            if (plane_keys)
                for (size_t i = b0; i < b0 + n; ++i) {
                    const float v0[3] = {geo[i], geo[M + i], geo[2 * M + i]};
                    plane_keys[i] = coplanar_key(v0, geo[9 * M + i], geo[10 * M + i], geo[11 * M + i], plane_inv_step);
                }
        }
    });
}

size_t surface(const float* geo, size_t M, const float* normals, const Hit* hits, const int64_t* idx,
               size_t k, const float* D, size_t n, float* out, const float* records) {
    std::atomic<size_t> bad{0};
    parallel_for(k, [&](size_t b, size_t e) {
        size_t local_bad = 0;
        for (size_t j = b; j < e; ++j) {
            const size_t i = idx ? index_at(idx, j, n) : j;
            const Hit& h = hits[i];
            const int32_t p = __atomic_load_n(&h.prim, __ATOMIC_RELAXED);
            if (p < 0 || size_t(p) >= M) {
                ++local_bad;
                continue;
            }
            const float d[3] = {D[i], D[n + i], D[2 * n + i]};
            SurfacePoint sp;
            surface_point_at(geo, M, normals, records, h, d, sp);
            for (int a = 0; a < 3; ++a) {
                out[size_t(a) * k + j] = sp.P[a];
                out[size_t(3 + a) * k + j] = sp.ng[a];
                out[size_t(6 + a) * k + j] = sp.P_off[a];
                if (normals) out[size_t(9 + a) * k + j] = sp.ns[a];
            }
        }
        if (local_bad) bad += local_bad;
    });
    return bad.load();
}

void face_normals(const double* vertices, size_t V, const int32_t* triangles, size_t M, float* normals, uint8_t* good) {
    parallel_for(M, [vertices, V, triangles, normals, good](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const double* c[3];
            for (int k = 0; k < 3; ++k) c[k] = vertex_of(vertices, V, triangles, 3 * i + size_t(k));
            double e1[3], e2[3];
            for (int a = 0; a < 3; ++a) {
                e1[a] = c[1][a] - c[0][a];
                e2[a] = c[2][a] - c[0][a];
            }
            const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                 e1[0] * e2[1] - e1[1] * e2[0]};
            const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            const bool ok = len > 0 && std::isfinite(len);
            for (int a = 0; a < 3; ++a) normals[3 * i + size_t(a)] = ok ? float(n[a] / len) : 0.0f;
            good[i] = ok;
        }
    });
}

void corner_rows(const float* per_corner, size_t M, size_t c, float* rows) {
    parallel_for(M, [per_corner, M, c, rows](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const float* p = per_corner + 3 * c * i;
            for (size_t a = 0; a < c; ++a) {
                rows[a * M + i] = p[a];
                rows[(c + a) * M + i] = p[c + a] - p[a];
                rows[(2 * c + a) * M + i] = p[2 * c + a] - p[a];
            }
        }
    });
}

bool normals_flat(const float* normals, const float* geo, size_t M, float tol) {
    std::atomic<bool> flat{true};
    parallel_for(M, [normals, geo, M, tol, &flat](size_t b, size_t e) {
        for (size_t i = b; i < e && flat.load(std::memory_order_relaxed); ++i)
            for (int c = 0; c < 3; ++c)
                for (int a = 0; a < 3; ++a)
                    if (!(std::fabs(normals[9 * i + size_t(3 * c + a)] - geo[size_t(9 + a) * M + i]) < tol)) {
                        flat.store(false, std::memory_order_relaxed);
                        return;
                    }
    });
    return flat.load();
}

}  // namespace dacrt

