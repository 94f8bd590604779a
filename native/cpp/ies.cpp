// IES profile lookup and registry (ies.h).
#include "ies.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <stdexcept>

namespace dacrt {

namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr float k2Pi = 6.28318530717958647692f;

// Cycles' util/math cubic_interp and inverse_lerp, their operation order
inline float cubic_interp(float a, float b, float c, float d, float x) {
    return 0.5f * (((d + 3.0f * (b - c) - a) * x + (2.0f * a - 5.0f * b + 4.0f * c - d)) * x + (c - a)) * x + b;
}
inline float inverse_lerp(float a, float b, float x) { return (x - a) / (b - a); }

// interpolate_ies_vertical: along v in column h; past an end that does not wrap the nearer
// inner point stands in
inline float vertical(const IesTable& t, bool wrap_vlow, bool wrap_vhigh, size_t v, float v_frac, size_t h) {
    const size_t vn = t.v.size();
    const float* col = t.I.data() + h * vn;
    const float b = col[v], c = col[v + 1];
    const float a = v > 0 ? col[v - 1] : (wrap_vlow ? col[1] : b);
    const float d = v + 2 < vn ? col[v + 2] : (wrap_vhigh ? col[vn - 2] : c);
    return cubic_interp(a, b, c, d, v_frac);
}

// A slot per distinct live table, its references counted under the mutex. An id is
// generation * kIesMaxTables + slot + 1, the generation bumped when the slot is freed: a record
// naming a released profile finds no table (rather than the slot's next one) until the slot has
// been reused kGenerations times. Ids stay below 2^24, exact in a record's float32.
constexpr int kGenerations = (1 << 24) / kIesMaxTables;
struct Slot {
    std::atomic<const IesTable*> table{nullptr};
    std::atomic<int> id{0};  // 0: free
    int refs = 0, generation = 0;
};
Slot g_slots[kIesMaxTables];
std::atomic<int> g_live{0};
std::mutex g_register;

}  // namespace

float ies_interp(const IesTable& t, float h_angle, float v_angle) {
    const size_t hn = t.h.size(), vn = t.v.size();
    const float v_low = t.v[0], v_high = t.v[vn - 1], h_low = t.h[0], h_high = t.h[hn - 1];
    // (a NaN lookup angle: Cycles' fraction is NaN, so 0; and no scan to run off a one-angle axis)
    if (std::isnan(v_angle) || std::isnan(h_angle)) return 0.0f;
    // Cycles' bounds tests in its form: a NaN or infinite table end lets angles through
    if (v_angle < v_low || v_angle >= v_high) return 0.0f;
    if (h_angle < h_low || h_angle >= h_high) return 0.0f;
    // Cycles' float32 tests: k2Pi - 1e-7f and kPi - 1e-7f round back to 2 pi and pi, so a
    // table ending at 360 (180) degrees does not wrap there (the inner point stands in)
    const bool wrap_h = h_low < 1e-7f && h_high > k2Pi - 1e-7f;
    const bool wrap_vlow = v_low < 1e-7f;
    const bool wrap_vhigh = v_high > kPi - 1e-7f;
    // Cycles' linear scans, in any order of angles: the first interval whose end is not < the
    // angle (>= it, or NaN); the last angle ends them (the bounds test), so an axis of one angle
    // gets here only where that angle is NaN, which ies_register refuses. A finite
    // interval past the first starts below the angle: only a repeated first angle gives a
    // zero-width one (0/0: NaN), and a NaN end a NaN fraction, both 0 below.
    size_t hi = 0, vi = 0;
    while (t.h[hi + 1] < h_angle) ++hi;
    while (t.v[vi + 1] < v_angle) ++vi;
    const float h_frac = inverse_lerp(t.h[hi], t.h[hi + 1], h_angle);
    const float v_frac = inverse_lerp(t.v[vi], t.v[vi + 1], v_angle);
    const float b = vertical(t, wrap_vlow, wrap_vhigh, vi, v_frac, hi);
    const float c = vertical(t, wrap_vlow, wrap_vhigh, vi, v_frac, hi + 1);
    float a = b, d = b;  // (Cycles: the current column stands in at both ends)
    if (hi > 0)
        a = vertical(t, wrap_vlow, wrap_vhigh, vi, v_frac, hi - 1);
    else if (wrap_h)  // the last column (360 degrees) is the first: the one before it
        a = vertical(t, wrap_vlow, wrap_vhigh, vi, v_frac, hn - 2);
    if (hi + 2 < hn)
        d = vertical(t, wrap_vlow, wrap_vhigh, vi, v_frac, hi + 2);
    else if (wrap_h)
        d = vertical(t, wrap_vlow, wrap_vhigh, vi, v_frac, 1);
    // Cycles' max(x, 0.0f) is x > 0 ? x : 0, so NaN (a NaN intensity, a 0/0 fraction) gives
    // 0; inf passes it but Cycles' film makes a non-finite contribution 0 (film_clamp_light)
    const float r = cubic_interp(a, b, c, d, h_frac);
    return r > 0.0f && r < INFINITY ? r : 0.0f;
}

float ies_direction(const IesTable& t, const float d[3]) {
    const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(len > 0)) return 0.0f;
    const float inv = 1.0f / len;
    const float x = d[0] * inv, y = d[1] * inv, z = d[2] * inv;
    const float mz = -z;
    const float v_angle = mz >= 1.0f ? 0.0f : (mz <= -1.0f ? kPi : std::acos(mz));  // safe_acosf
    const float h_angle = std::atan2(x, y) + kPi;
    return ies_interp(t, h_angle, v_angle);
}

const IesTable* ies_table(int id) {
    if (id < 1 || id > kIesMaxTables * kGenerations) return nullptr;
    const Slot& s = g_slots[(id - 1) % kIesMaxTables];
    if (s.id.load(std::memory_order_acquire) != id) return nullptr;
    return s.table.load(std::memory_order_acquire);
}

int ies_register(std::vector<float> h, std::vector<float> v, std::vector<float> I) {
    if (h.empty() || v.empty() || I.size() != h.size() * v.size())
        throw std::invalid_argument("an IES table needs >= 1 horizontal and vertical angle and H x V values");
    // Any angles in any order and any intensities, as Cycles keeps them, but for an axis of one
    // NaN angle: Cycles' bounds test then lets angles through and its scan reads past the axis
    // (one infinite angle fails every angle there: 0).
    if (h.size() == 1 && std::isnan(h[0]))
        throw std::invalid_argument("an IES horizontal axis of one angle must not have it NaN");
    if (v.size() == 1 && std::isnan(v[0]))
        throw std::invalid_argument("an IES vertical axis of one angle must not have it NaN");
    const std::lock_guard<std::mutex> lock(g_register);
    Slot* free_slot = nullptr;
    for (Slot& s : g_slots) {
        if (s.refs == 0) {
            if (!free_slot) free_slot = &s;
            continue;
        }
        const IesTable* t = s.table.load(std::memory_order_relaxed);
        if (t->h == h && t->v == v && t->I == I) {
            ++s.refs;
            return s.id.load(std::memory_order_relaxed);
        }
    }
    if (!free_slot)
        throw std::invalid_argument("too many distinct IES profiles alive at once (" + std::to_string(kIesMaxTables) +
                                    ")");
    Slot& s = *free_slot;
    const int id = s.generation * kIesMaxTables + int(&s - g_slots) + 1;
    s.refs = 1;
    s.table.store(new IesTable{std::move(h), std::move(v), std::move(I)}, std::memory_order_release);
    s.id.store(id, std::memory_order_release);
    g_live.fetch_add(1, std::memory_order_relaxed);
    return id;
}

void ies_release(int id) {
    if (id < 1 || id > kIesMaxTables * kGenerations) return;
    const std::lock_guard<std::mutex> lock(g_register);
    Slot& s = g_slots[(id - 1) % kIesMaxTables];
    if (s.refs == 0 || s.id.load(std::memory_order_relaxed) != id || --s.refs > 0) return;
    // no handle holds it, so no render reads it: unpublish, then delete
    s.id.store(0, std::memory_order_release);
    delete s.table.exchange(nullptr, std::memory_order_acq_rel);
    s.generation = (s.generation + 1) % kGenerations;
    g_live.fetch_sub(1, std::memory_order_relaxed);
}

int ies_live() { return g_live.load(std::memory_order_relaxed); }

std::string ies_id_error(float id) {
    if (id == 0) return {};
    const bool whole = std::fabs(id) < 2e9f && float(int(id)) == id;  // (int of NaN or 1e30: undefined)
    if (!whole || !ies_table(int(id)))
        return "ies " + (whole ? std::to_string(int(id)) : std::to_string(id)) +
               " is not a live IES profile id (never registered, or its last IesProfile handle was released; 0 = none)";
    return {};
}

float ies_lamp_factor(float id, const float m3[9], const float from_light[3]) {
    const IesTable* t = ies_table(int(id));
    if (!t) return 0.0f;
    float local[3];
    for (int r = 0; r < 3; ++r)
        local[r] = m3[3 * r] * from_light[0] + m3[3 * r + 1] * from_light[1] + m3[3 * r + 2] * from_light[2];
    return ies_direction(*t, local);
}

}  // namespace dacrt
