// Instruction-set selection at run time and the multithreaded driver of a trace call.
#pragma once
#include <memory>
#include <shared_mutex>
#include <string>
#include <vector>

#include "kernel.h"

namespace dacrt {

enum class Isa { Portable, Avx2, Avx512 };

std::vector<std::string> supported_isas();
std::string isa_name(Isa isa);
// "" -> best the CPU runs; otherwise that name, which must be supported (throws otherwise).
Isa resolve_isa(const std::string& requested);
FieldsFn fields_fn(Isa isa);  // the ISA's SIMD check of ray fields

// The instruction set of the lane kernels compiled as named copies per instruction set (noise.cpp,
// envlanes.cpp): the widest the CPU runs, or a narrower one DACRT_ISA names (a wider one it lacks,
// or any other name: the widest), so that tests compare the copies on one machine.
Isa lane_isa();

// Of a lane kernel's portable, AVX2 and AVX-512 copies, the one lane_isa() names.
template <class Fn>
Fn lane_copy(Fn portable, Fn avx2, Fn avx512) {
    const Isa isa = lane_isa();
    return isa == Isa::Avx512 ? avx512 : (isa == Isa::Avx2 ? avx2 : portable);
}

struct TraceResult {
    Stats stats;
    int threads = 1;
    int leaf_size = 0;  // the leaf size the call used (a Config's 0 resolved per ISA)
    double seconds = 0.0;
    double order_seconds = 0.0;  // of seconds: storing the triangles in the kept top's order
};

// The shared top levels of a scene's partition (kernel.h SharedTop: the split triangle ids and
// the splits of every node a batch reached, down to ~16 triangles), kept between the trace
// calls of one scene that use the same partition settings: the batches of one frame. Those
// splits depend on the triangles only (median; SAH's ray-count test in adaptive mode is made
// by the batch that splits the node), so later batches skip them; they are most of the
// partitioning work when a batch has fewer rays than the scene has triangles (an animation
// frame at low samples). Reset when the settings change; any batch adds to it. The scene owns
// it, so it lives exactly as long as the scene.
struct TopCache {
    std::shared_mutex lock;  // calls share it; a reset takes it alone
    bool ready = false;
    Partition partition = Partition::Adaptive;
    int leaf_size = 0;
    float sah_ratio = 0.0f;
    std::vector<uint32_t> ids;
    std::unique_ptr<NodePool> pool;
    uint32_t ordered_nodes = 0;  // the pool's size when the triangles were last stored in ids' order
};

// Validates nothing (see ray.h validate_rays); traces rays[0, n) with `threads` threads
// (0 = all cores). Independent ray chunks per thread, as in the paper, with dynamic hand-out.
// cache: the scene's kept top levels (null: built for this call only).
TraceResult trace(TriangleSet& ts, Ray* rays, size_t n, const TraceJob& job, int threads, Isa isa,
                  TopCache* cache = nullptr);

}  // namespace dacrt
