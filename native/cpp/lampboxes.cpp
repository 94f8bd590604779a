// LampBoxes (lampboxes.h): LampBVH's padded slab test, kRays rays per lane loop against each
// box. Compiled with -fno-trapping-math (CMakeLists.txt), without which GCC keeps the selects
// after the divisions as branches, and for AVX2 too (target_clones); every lane's operations
// are LampBVH::Slab's, in its order (-ffp-contract=off), so every copy gives the same bits.
#include "lampboxes.h"

#include <cstring>
#include <limits>

#include "lampbvh.h"

namespace dacrt {

LampBoxes::LampBoxes(const LampRecord* rec, const int32_t* lamps, size_t nl) {
    for (size_t k = 0; k < nl && k < kMaxLamps; ++k) {
        float lo[3], hi[3];
        if (!LampBVH::padded_box(rec[lamps[k]], lo, hi)) continue;
        box_.insert(box_.end(), lo, lo + 3);
        box_.insert(box_.end(), hi, hi + 3);
        which_.push_back(int32_t(k));
    }
}

namespace {

inline int sign_clear(float x) {  // !std::signbit(x), as an int lane
    uint32_t b;
    std::memcpy(&b, &x, sizeof b);
    return int(~b >> 31);
}

// The test itself, a free function of internal linkage: target_clones on the member function
// made GCC's LTO link warn that LampBoxes::meets violates the ODR (its clones and ifunc against
// the header's plain declaration).
__attribute__((target_clones("avx2", "default")))
void meets_lanes(const float* box, const int32_t* which, size_t nb, const float* O, const float* D,
                 const float* tmax, size_t t_step, size_t n, size_t i0, size_t count,
                 uint64_t out[LampBoxes::kRays]) {
    constexpr size_t K = LampBoxes::kRays;
    constexpr float inf = std::numeric_limits<float>::infinity();
    const float c = LampBVH::kSlack;
    // LampBVH::Slab per lane; lanes past count get a harmless ray (their bits are dropped)
    float inv_p[3][K], inv_m[3][K], off_lo[3][K], off_hi[3][K], t_end[K];
    int lower_p[3][K], upper_m[3][K];
    float o[3][K], d[3][K], tm[K];
    for (size_t q = 0; q < K; ++q) {
        for (int a = 0; a < 3; ++a) o[a][q] = 0.0f, d[a][q] = float(a == 2);
        tm[q] = 0.0f;
    }
    for (size_t q = 0; q < count; ++q) {
        for (int a = 0; a < 3; ++a) {
            o[a][q] = O[size_t(a) * n + i0 + q];
            d[a][q] = D[size_t(a) * n + i0 + q];
        }
        tm[q] = tmax[(i0 + q) * t_step];
    }
    for (size_t q = 0; q < K; ++q) {
        // M = std::max({|O0|, |O1|, |O2|}): the first of the largest
        float M = std::fabs(o[0][q]);
        const float m1 = std::fabs(o[1][q]), m2 = std::fabs(o[2][q]);
        M = M < m1 ? m1 : M;
        M = M < m2 ? m2 : M;
        for (int a = 0; a < 3; ++a) {
            const float ap = d[a][q] + c, am = d[a][q] - c;
            inv_p[a][q] = 1.0f / ap;
            inv_m[a][q] = 1.0f / am;
            lower_p[a][q] = sign_clear(ap);
            upper_m[a][q] = sign_clear(am);
            off_lo[a][q] = -o[a][q] - c * M;
            off_hi[a][q] = -o[a][q] + c * M;
        }
        t_end[q] = tm[q] + c * (M + tm[q]);
    }
    uint64_t bits[K] = {};
    for (size_t j = 0; j < nb; ++j) {
        const float* bx = box + 6 * j;
        int hit[K];
        for (size_t q = 0; q < K; ++q) {  // LampBVH::Slab::meets
            float tn = 0.0f, tf = t_end[q];
            for (int a = 0; a < 3; ++a) {
                const float x = (bx[a] + off_lo[a][q]) * inv_p[a][q], y = (bx[3 + a] + off_hi[a][q]) * inv_m[a][q];
                const float xn = lower_p[a][q] ? x : -inf, xf = lower_p[a][q] ? inf : x;
                const float yn = upper_m[a][q] ? -inf : y, yf = upper_m[a][q] ? y : inf;
                tn = xn > tn ? xn : tn;
                tf = xf < tf ? xf : tf;
                tn = yn > tn ? yn : tn;
                tf = yf < tf ? yf : tf;
            }
            hit[q] = tn <= tf;
        }
        // most boxes meet none of the rays: a branch per box and group, not per ray
        int any = 0;
        for (size_t q = 0; q < K; ++q) any |= hit[q];
        if (!any) continue;
        const uint64_t bit = uint64_t(1) << which[j];
        for (size_t q = 0; q < K; ++q) bits[q] |= hit[q] ? bit : 0;
    }
    for (size_t q = 0; q < K; ++q) out[q] = q < count ? bits[q] : 0;
}

}  // namespace

void LampBoxes::meets(const float* O, const float* D, const float* tmax, size_t t_step, size_t n, size_t i0,
                      size_t count, uint64_t out[kRays]) const {
    meets_lanes(box_.data(), which_.data(), which_.size(), O, D, tmax, t_step, n, i0, count, out);
}

}  // namespace dacrt
