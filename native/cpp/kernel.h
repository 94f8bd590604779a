// Entry points of the per-ISA kernels. Each is the same template code (filter, partition, leaf,
// trace) compiled in its own translation unit with its own instruction set and namespace.
#pragma once
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <new>
#include <vector>

#include "interrupt.h"
#include "ray.h"
#include "triangles.h"

namespace dacrt {

// Bounds of a set of triangles during partitioning.
struct NodeBounds {
    float lo[3], hi[3];    // box of the triangles
    float clo[3], chi[3];  // box of their centres
};

// The top levels of the recursion, shared by all threads of one call. The paper's threads
// repeat the top partitioning steps per ray batch; here the first thread to reach a top node
// partitions the shared id array once and publishes the split, the others reuse it. Deeper
// nodes are traced on a private copy of their triangle ids. A top node's ids are only read for
// a leaf when the node cannot be split further, or copied under the node's lock, so no thread
// ever reads a range that another is reordering.
struct SharedNode {
    std::atomic<int> state{0};  // 0 unsplit, 1 locked (being split or its ids copied), 2 split published
    uint32_t k = 0;             // left child = ids[0, k)
    uint32_t child = 0;         // pool index of the left child (right: child + 1); 0 = none, trace privately
    int axis = 0;
    NodeBounds L{}, R{};
};

// The shared nodes, allocated in pairs as splits are published (a spatial-median tree over
// unevenly dense geometry is far deeper than log2 of its size, so a fixed heap-ordered table
// would cut it off early). Blocks never move; a reader reaches a node only through its parent's
// published split, which orders the block's allocation before the read.
class NodePool {
  public:
    static constexpr uint32_t kBlock = 4096, kMaxBlocks = 4096;  // at most 16M nodes
    NodePool() { blocks_[0].reset(new SharedNode[kBlock]); used_ = 2; }  // 1: the root (0: none)
    SharedNode& at(uint32_t i) { return blocks_[i / kBlock][i % kBlock]; }
    uint32_t used() {
        std::lock_guard<std::mutex> g(m_);
        return used_;
    }
    // Index of two fresh consecutive nodes, or 0 when the pool is full or a block cannot be
    // had. Never throws: the caller holds its node locked (state 1), and a throw there left
    // the node locked for good, so every other thread reaching it spun forever.
    uint32_t alloc2() {
        std::lock_guard<std::mutex> g(m_);
        if (used_ % kBlock == 0) {
            const uint32_t b = used_ / kBlock;
            if (b >= kMaxBlocks) return 0;
            blocks_[b].reset(new (std::nothrow) SharedNode[kBlock]);
            if (!blocks_[b]) return 0;
        }
        used_ += 2;
        return used_ - 2;
    }

  private:
    std::mutex m_;
    std::unique_ptr<SharedNode[]> blocks_[kMaxBlocks];
    uint32_t used_ = 0;
};

struct SharedTop {
    uint32_t* ids = nullptr;
    NodePool* pool = nullptr;     // root: index 1
    int max_depth = 0;            // nodes at depth < max_depth are shared
    size_t min_tris = 0;          // smaller nodes are traced privately
    float ray_scale = 1.0f;       // total rays / chunk rays: the adaptive choice at shared nodes
};

// Work stealing (dispatch.cpp): a thread out of chunks takes the farther child of a node that
// another thread has still to visit, with a copy of that node's rays renumbered 0..n-1 and
// hits of its own, merged into the caller's afterwards (closest t, then lowest triangle, the
// leaf's own rule, so hits stay a function of ray and triangles alone).
struct StolenTask {
    std::vector<Ray> rays;
    std::vector<uint32_t> own_ids;  // a private subtree's triangle ids (the owner reuses its scratch)
    uint32_t* ids = nullptr;        // own_ids, or the shared top's ids of a shared child
    size_t nt = 0;
    NodeBounds nb{};
    uint64_t depth = 0;
    uint32_t h = 0;                 // the shared child's pool index (with shared)
    bool shared = false;
    std::vector<uint32_t> map;      // local id -> the caller's id (~0u: an id out of range)
    std::vector<int32_t> skip;      // by local id (empty: no skip array)
    std::vector<Hit> hits;          // by local id
    std::vector<uint8_t> occluded;  // by local id
    float origin_abs_max = 0.0f;
    int filter_kind = 0;
    Ray* fix = nullptr;             // the caller's records that hold these rays (their chunk's), whose
    size_t fix_n = 0;               // tfar is set from the merged hits
};

struct StealBoard {
    // Nodes handed over: from kMinRays rays (fewer are not worth a copy) to kMaxRays. Taking
    // the largest pending node instead (all of a chunk's rays near the top) copied up to 16 MB
    // a steal, and on a loaded machine, where a thread descheduled for a while makes the other
    // steal, the halves went back and forth: dragon diffuse rays +10% CPU time, no faster.
    static constexpr size_t kMinRays = 4096, kMaxRays = 65536;
    std::mutex m;
    std::condition_variable cv;
    std::atomic<int> want{0};  // waiting - offered: read by busy threads at every node entry
    int waiting = 0;           // idle threads waiting for a task (under m, as all below)
    int offered = 0;           // tasks being copied or queued
    int working = 0;           // threads tracing a chunk or a task
    std::deque<StolenTask*> queue;
    std::vector<std::unique_ptr<StolenTask>> all;  // merged when the call ends

    void update() { want.store(waiting - offered, std::memory_order_relaxed); }
    // Whether a busy thread should copy a task for a waiting one (then it must publish or withdraw).
    bool reserve() {
        std::lock_guard<std::mutex> g(m);
        if (waiting - offered <= 0) return false;
        ++offered;
        update();
        return true;
    }
    void withdraw() {
        std::lock_guard<std::mutex> g(m);
        --offered;
        update();
    }
    void publish(std::unique_ptr<StolenTask> t) {
        std::lock_guard<std::mutex> g(m);
        queue.push_back(t.get());
        all.push_back(std::move(t));
        cv.notify_all();
    }
};

// What the field check (validate.h) learns about a batch besides its validity.
struct BatchInfo {
    float origin_abs_max = 0.0f;  // largest |origin coordinate| (box padding)
    bool odd_dirs = false;        // a direction component is denormal or > 2^125 in size (filter.h)
    bool far_origins = false;     // set per group by trace() (dispatch.cpp): the precise box test
    // Input: the index of the first checked ray in the batch. Output: whether every checked
    // ray k has id first_id + k (then the ids are a permutation without any id marking).
    size_t first_id = 0;
    bool ids_in_order = true;
    void merge(const BatchInfo& o) {
        origin_abs_max = origin_abs_max > o.origin_abs_max ? origin_abs_max : o.origin_abs_max;
        odd_dirs = odd_dirs || o.odd_dirs;
        ids_in_order = ids_in_order && o.ids_in_order;
    }
};

struct TraceJob {
    const TriangleSet* ts;
    Config cfg;
    Query query;
    Hit* hits;            // Closest: output by ray id
    uint8_t* occluded;    // Any: output by ray id
    const int32_t* skip;  // optional, by ray id: triangle the ray must ignore (-1: none)
    BatchInfo batch;      // from the field check of the batch
    SharedTop* top;       // shared top levels of this call
    // optional, by triangle: visibility bits; a triangle is traced when (mask & visible) != 0,
    // so one scene serves ray kinds that see slightly different triangle subsets
    const uint8_t* mask = nullptr;
    uint8_t visible = 0xFF;
    // Length of hits / occluded / skip. Ids were validated, but the rays are the caller's
    // array, which another Python thread may rewrite while the GIL is released: every id is
    // checked against this where it indexes (a rewritten ray gets a wrong answer, never a
    // write out of bounds). Set by trace().
    size_t num_ids = 0;
    // optional: lets the caller stop the call part-way (interrupt.h); trace() then throws
    Interrupt* interrupt = nullptr;
    StealBoard* steal = nullptr;  // null: no work stealing
};

// Trace rays[0, n) against all valid triangles; ids: the thread's scratch of ts.valid_ids.size().
using ChunkFn = void (*)(const TraceJob&, Ray*, size_t, uint32_t*, Stats&);
// Trace a stolen task's rays (with its own hits) on the thread's id scratch.
using TaskFn = void (*)(const TraceJob&, StolenTask&, uint32_t*, Stats&);
// Whether every ray's fields are valid (validate.h); also what the trace needs to know of them.
using FieldsFn = bool (*)(const Ray*, size_t, BatchInfo&);
namespace portable {
void trace_chunk(const TraceJob&, Ray*, size_t, uint32_t*, Stats&);
void trace_task(const TraceJob&, StolenTask&, uint32_t*, Stats&);
bool fields_valid(const Ray*, size_t, BatchInfo&);
}
namespace avx2 {
void trace_chunk(const TraceJob&, Ray*, size_t, uint32_t*, Stats&);
void trace_task(const TraceJob&, StolenTask&, uint32_t*, Stats&);
bool fields_valid(const Ray*, size_t, BatchInfo&);
}
namespace avx512 {
void trace_chunk(const TraceJob&, Ray*, size_t, uint32_t*, Stats&);
void trace_task(const TraceJob&, StolenTask&, uint32_t*, Stats&);
bool fields_valid(const Ray*, size_t, BatchInfo&);
}

}  // namespace dacrt
