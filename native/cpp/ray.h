// Ray and hit records shared by every layer of the native core.
//
// The ray record is exactly 32 bytes (one AVX register), as in Afra 2012: filtering moves whole
// records, so it must stay small. No reciprocal direction is stored; filtering computes it in
// registers. tfar doubles as the current closest-hit distance during traversal.
#pragma once
#include <chrono>
#include <cstdint>
#if defined(__x86_64__) || defined(__i386__)
#include <x86intrin.h>
#endif

namespace dacrt {

struct alignas(4) Ray {
    float org[3];
    float dir[3];
    float tfar;
    uint32_t id;
};
static_assert(sizeof(Ray) == 32, "ray record must be 32 bytes");

struct Hit {
    float t;
    int32_t prim;  // -1 = miss
    float u, v;    // barycentric weights of vertices 1 and 2
};
static_assert(sizeof(Hit) == 16, "hit record must be 16 bytes");

// tfar written into a ray that an occlusion query has found blocked: the box test rejects it
// from then on, which is the early termination of found rays.
constexpr float kOccludedTfar = -1.0f;

enum class Partition : int { Adaptive = 0, Median = 1, Sah = 2 };
enum class Query : int { Closest = 0, Any = 1 };

struct Config {
    Partition partition = Partition::Adaptive;
    // A node becomes a leaf at most leaf_size triangles or at most leaf_rays active rays. The
    // paper uses 8 for both (8-wide AVX). Measured here (bench tracer, SF 268K triangles, and a
    // dragon frame's batches), 32 rays (two 16-wide groups) are 6-14% faster: below ~2 SIMD
    // groups of rays one more partitioning step costs more than it saves. leaf_size 0 (the
    // default) is kDefaultLeafSize in dispatch.cpp: 8 triangles.
    int leaf_size = 0;
    int leaf_rays = 32;
    float sah_ratio = 128.0f;  // adaptive: SAH where active rays / triangles exceeds this (bench partition)
    size_t chunk_rays = 0;   // rays per independently traced chunk; 0 = automatic
};

// Cheap clock for the per-phase timers in Stats: the time-stamp counter (~9 ns a read, a third
// of steady_clock's), converted to seconds with a steady_clock measurement around each call.
inline uint64_t phase_clock() {
#if defined(__x86_64__) || defined(__i386__)
    return __rdtsc();
#else
    return uint64_t(std::chrono::steady_clock::now().time_since_epoch().count());
#endif
}

struct Stats {
    uint64_t rays = 0;
    uint64_t box_tests = 0;
    uint64_t box_hits = 0;  // rays kept active by the box tests
    uint64_t filter_skips = 0;  // nodes whose filter was skipped (most sampled rays hit the box)
    uint64_t tri_tests = 0;
    uint64_t partition_steps = 0;
    uint64_t median_steps = 0;
    uint64_t sah_steps = 0;
    uint64_t leaves = 0;
    uint64_t double_fallbacks = 0;
    uint64_t max_depth = 0;
    uint64_t steals = 0;  // subtrees handed to an idle thread (work stealing, dispatch.cpp)
    // Per-phase time in phase_clock() ticks, summed over threads: read at node
    // granularity (3 clock reads per node), never per ray; subtrees of few rays are timed as a
    // whole and split between the phases by sampled nodes (Tracer::timing in trace.h).
    uint64_t filter_ticks = 0;
    uint64_t partition_ticks = 0;
    uint64_t leaf_ticks = 0;
    void add(const Stats& o) {
        rays += o.rays; box_tests += o.box_tests; box_hits += o.box_hits; filter_skips += o.filter_skips;
        tri_tests += o.tri_tests;
        partition_steps += o.partition_steps; median_steps += o.median_steps;
        sah_steps += o.sah_steps; leaves += o.leaves; double_fallbacks += o.double_fallbacks;
        steals += o.steals;
        filter_ticks += o.filter_ticks; partition_ticks += o.partition_ticks; leaf_ticks += o.leaf_ticks;
        if (o.max_depth > max_depth) max_depth = o.max_depth;
    }
};

}  // namespace dacrt
