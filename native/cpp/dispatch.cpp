// Run-time ISA dispatch and threading (see dispatch.h).
//
// Multithreading: independent ray chunks traced in parallel as in the paper (one per thread,
// handed out dynamically when chunk_rays asks for more), cut at the median origin
// (chunkorder.h), plus shared top levels (kernel.h SharedTop) so the threads do not repeat the
// large partitioning steps, and work stealing (kernel.h StealBoard) so that chunks of unequal
// cost finish together. Allocations of a call: the shared triangle id array, one id scratch
// per thread (4 bytes per triangle each) and the shared nodes (two per published split);
// per ray only the copies a stolen node takes (its rays, ids and hits).
#include "dispatch.h"
#include "chunkorder.h"
#include "parallel.h"

#include <strings.h>

#include <algorithm>
#include <cstdlib>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <stdexcept>

namespace dacrt {

static constexpr size_t kMinChunkRays = 1 << 16;
static constexpr size_t kMinKeptChunkRays = 1 << 10;
static constexpr size_t kSharedMinTris = 32;
static constexpr int kKeptMaxDepth = 48;

static bool cpu_has_avx2() {
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
           __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
}
static bool cpu_has_avx512() {
    return cpu_has_avx2() && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
           __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
           __builtin_cpu_supports("avx512cd");
}

std::string isa_name(Isa isa) {
    switch (isa) {
        case Isa::Avx512: return "avx512";
        case Isa::Avx2: return "avx2";
        default: return "portable";
    }
}

std::vector<std::string> supported_isas() {
    std::vector<std::string> v{"portable"};
    if (cpu_has_avx2()) v.push_back("avx2");
    if (cpu_has_avx512()) v.push_back("avx512");
    return v;
}

Isa resolve_isa(const std::string& req) {
    if (req.empty()) return cpu_has_avx512() ? Isa::Avx512 : (cpu_has_avx2() ? Isa::Avx2 : Isa::Portable);
    if (req == "portable") return Isa::Portable;
    if (req == "avx2") {
        if (!cpu_has_avx2()) throw std::runtime_error("DACRT_ISA=avx2 requested but this CPU lacks AVX2/FMA");
        return Isa::Avx2;
    }
    if (req == "avx512") {
        if (!cpu_has_avx512()) throw std::runtime_error("DACRT_ISA=avx512 requested but this CPU lacks AVX-512 (F/VL/DQ/BW/CD)");
        return Isa::Avx512;
    }
    throw std::runtime_error("unknown ISA '" + req + "' (expected portable, avx2 or avx512)");
}

Isa lane_isa() {
    const Isa best = resolve_isa("");
    const char* env = std::getenv("DACRT_ISA");
    Isa isa = best;
    if (env && strcasecmp(env, "portable") == 0) isa = Isa::Portable;
    if (env && strcasecmp(env, "avx2") == 0 && best != Isa::Portable) isa = Isa::Avx2;
    return isa;
}

FieldsFn fields_fn(Isa isa) {
    return isa == Isa::Avx512 ? avx512::fields_valid : (isa == Isa::Avx2 ? avx2::fields_valid : portable::fields_valid);
}

// The leaf size a Config's leaf_size 0 stands for: 8 triangles on every kernel. On the 8-wide
// AVX2 kernel (a Zen 3 machine without AVX-512) 8 was 3-6% faster than 16 on most sets of San
// Francisco and dragon rays. On AVX-512, 16 was best until the filter's 64-ray runs made
// splitting cheaper; then (bench tracer, 10K room, dragon, San Francisco; 1 and 2 threads) 8
// gave diffuse rays +0..+9%, shadow rays +1..+9%, camera rays -3..+6%, and a Cornell box
// render's tracing -13% (it tests ~16-triangle leaves brute force).
constexpr int kDefaultLeafSize = 8;

// Far ray origins. The filter pads every node box by ~2^-19 of (the box's largest |coordinate|
// + the batch's largest |origin coordinate|), which the watertight test needs for a ray of that
// origin (trace.h). One far origin padded every box of its batch: 50,000 rays among 64K small
// triangles took 0.02 s, with one origin at 1e5 0.5 s, at 1e6 21 s; a render inside a 10 km
// dome ran 30x slower than inside a 1 km one. So rays whose origin pads a box by more than an
// eighth of a small triangle (TriangleSet::fine_extent) are traced as groups of their own, each
// spanning 16x in |origin|, with the precise box test (filter.h: the fast one widens t by
// 2^-10 of itself, ~10 at 10 km, and kept every ray near a small triangle's box). Hits do not
// change: the leaf's check uses each ray's own origin, and every group pads enough for its
// rays. Measured: those 50,000 rays with one origin at 1e6 0.02 s; a 63K-triangle Suzanne in a
// 10 km dome, 160x120 at 16 spp, 19-32 s -> 0.6 s (a 100 m dome 1.6 s). Tried for every ray on
// San Francisco's 1M rays (1 thread), the precise test culled more (camera rays: 25% fewer
// triangle tests) but cost more than it saved on diffuse rays (+9% time), so near rays keep
// the fast one.
struct Span {
    size_t b, e;
    float origin_abs_max;
    bool far;
};

static float origin_abs(const Ray& r) {
    return std::max(std::fabs(r.org[0]), std::max(std::fabs(r.org[1]), std::fabs(r.org[2])));
}

// Reorders rays[0, n) into spans of near rays, then far ones by origin magnitude.
static std::vector<Span> origin_groups(const TriangleSet& ts, Ray* rays, size_t n, float origin_abs_max) {
    const float near = std::max(ts.fine_extent * 0x1p16f, FLT_MIN);
    if (!(origin_abs_max > near)) return {Span{0, n, origin_abs_max, false}};
    const int e0 = std::ilogb(near);
    auto group = [&](const Ray& r) {
        const float a = origin_abs(r);
        return a <= near ? 0 : 1 + (std::ilogb(a) - e0) / 4;
    };
    std::vector<Span> spans;
    size_t b = 0;
    for (int g = 0; b < n; ++g) {  // groups ascending; at most ~64 (float exponents / 4)
        Ray* mid = std::partition(rays + b, rays + n, [&](const Ray& r) { return group(r) == g; });
        const size_t e = size_t(mid - rays);
        if (e == b) continue;
        float m = 0.0f;
        for (size_t i = b; i < e; ++i) m = std::max(m, origin_abs(rays[i]));
        spans.push_back(Span{b, e, m, g > 0});
        b = e;
    }
    return spans;
}

// The stolen tasks' hits into the caller's (closest t, then lowest triangle: the leaf's rule,
// so the result does not depend on who traced what), then the tfar of the caller's records
// whose hit a task found, as the owner's leaves would have set it (the hit's distance, or
// kOccludedTfar). Those records have moved within their chunk since, so the chunk is scanned
// for them, marked in a bitmap by id: reading every record's hit instead (a random access
// per record) cost the dragon's 1M diffuse rays ~9% CPU time a call.
static void merge_stolen(StealBoard& board, const TraceJob& job, size_t n, int T) {
    std::vector<std::pair<Ray*, size_t>> chunks;
    for (const auto& t : board.all) chunks.emplace_back(t->fix, t->fix_n);
    std::sort(chunks.begin(), chunks.end());
    chunks.erase(std::unique(chunks.begin(), chunks.end()), chunks.end());
    std::vector<uint64_t> changed((n + 63) / 64, 0);
    // a ray may be in several tasks (a stolen node's task stolen from again): each thread
    // merges the ids of its own range (whole bitmap words), then fixes its share of records
    run_workers(T, [&](int w) {
        const size_t lo = (n * size_t(w) / size_t(T)) & ~size_t(63);
        const size_t hi = w + 1 == T ? n : (n * size_t(w + 1) / size_t(T)) & ~size_t(63);
        for (const auto& t : board.all) {
            const size_t m = t->map.size();
            for (size_t k = 0; k < m; ++k) {
                const uint32_t g = t->map[k];
                if (g < lo || g >= hi) continue;
                if (job.query == Query::Any) {
                    if (!t->occluded[k] || job.occluded[g] == 1) continue;
                    job.occluded[g] = 1;
                } else {
                    const Hit& l = t->hits[k];
                    Hit& h = job.hits[g];
                    if (!(l.prim >= 0 && (h.prim < 0 || l.t < h.t || (l.t == h.t && l.prim < h.prim)))) continue;
                    h = l;
                }
                changed[g >> 6] |= uint64_t(1) << (g & 63);
            }
        }
    });
    run_workers(T, [&](int w) {
        for (const auto& c : chunks) {
            const size_t b = c.second * size_t(w) / size_t(T), e = c.second * size_t(w + 1) / size_t(T);
            for (size_t i = b; i < e; ++i) {
                Ray& r = c.first[i];
                const uint32_t id = r.id;
                if (id >= n || !(changed[id >> 6] >> (id & 63) & 1)) continue;
                r.tfar = job.query == Query::Any ? kOccludedTfar : job.hits[id].t;
            }
        }
    });
}

// Stores the triangles in the kept top's id order, so that a node's triangles fill a contiguous
// range of slots and a leaf's records share cache lines instead of being fetched one miss each
// (in the caller's order a late batch's leaves spent most of their time on those loads). Done
// after the frame's first call and again whenever the top's splits have doubled since (a later
// split only permutes a node's range, which stays contiguous). Measured on a recorded 4-spp
// dragon frame (100K triangles, 9 calls): trace CPU 88-89 -> 55-75 ms, the late calls 1.5-2x
// faster; the order costs ~35 ns a triangle (README, "Where the time goes"). Returns its
// seconds (0: not done).
static double store_in_top_order(TriangleSet& ts, TopCache& cache) {
    const auto t0 = std::chrono::steady_clock::now();
    std::unique_lock<std::shared_mutex> alone(cache.lock);
    if (!cache.ready || !cache.pool) return 0.0;
    const uint32_t nodes = cache.pool->used();
    if (nodes <= 2 || nodes < 2 * cache.ordered_nodes) return 0.0;  // 2: the root alone, no split
    try {
        ts.reorder(cache.ids.data());
    } catch (...) {  // out of memory: nothing was changed, and the order only saves time
        return 0.0;
    }
    for (size_t i = 0; i < cache.ids.size(); ++i) cache.ids[i] = uint32_t(i);
    cache.ordered_nodes = nodes;
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

TraceResult trace(TriangleSet& ts, Ray* rays, size_t n, const TraceJob& job_in, int threads, Isa isa,
                  TopCache* cache) {
    TraceJob job = job_in;
    if (job.cfg.leaf_size == 0) job.cfg.leaf_size = kDefaultLeafSize;
    const auto t0 = std::chrono::steady_clock::now();
    TraceResult res;
    res.stats.rays = n;
    res.leaf_size = job.cfg.leaf_size;
    ChunkFn fn = isa == Isa::Avx512 ? avx512::trace_chunk : (isa == Isa::Avx2 ? avx2::trace_chunk : portable::trace_chunk);
    const size_t nt = ts.valid_ids.size();
    if (n > 0 && nt > 0) {
        int T = threads > 0 ? std::min(threads, max_workers()) : default_threads();
        int levels = 0;  // a balanced tree's depth to nodes of about kSharedMinTris triangles
        while ((nt >> levels) > kSharedMinTris) ++levels;
        std::vector<uint32_t> own_ids;
        std::unique_ptr<NodePool> own_pool;
        std::shared_lock<std::shared_mutex> kept;
        SharedTop top;
        // Any batch sets the kept top, a small one too: a frame whose batches are all small (1 spp
        // on a big scene, a renderer's probe rays first) otherwise partitioned the whole scene
        // once per batch on one thread (bmw27, 1.7M triangles, 1 spp: 1.5 s of tracing, now
        // 0.14 s). In adaptive mode a node's split follows the ray count of the batch that
        // makes it, but SAH is only ever chosen for nodes of < rays / sah_ratio triangles, which
        // a small batch rarely reaches with enough rays to split.
        bool use_kept = false;
        if (cache) {
            const Config& c = job.cfg;
            auto matches = [&] {
                return cache->ready && cache->partition == c.partition && cache->leaf_size == c.leaf_size &&
                       cache->sah_ratio == c.sah_ratio;
            };
            for (;;) {
                kept = std::shared_lock<std::shared_mutex>(cache->lock);
                if (matches()) {
                    use_kept = true;
                    break;
                }
                kept.unlock();
                std::unique_lock<std::shared_mutex> reset(cache->lock);
                if (!matches()) {  // first batch, or new settings: start over
                    cache->ids = ts.valid_ids;
                    cache->pool.reset(new NodePool());
                    cache->partition = c.partition;
                    cache->leaf_size = c.leaf_size;
                    cache->sah_ratio = c.sah_ratio;
                    cache->ordered_nodes = 0;
                    cache->ready = true;
                }
            }  // then take it shared (another call may have reset it to its settings: again)
        }
        if (use_kept) {
            top.ids = cache->ids.data();
            top.pool = cache->pool.get();
        } else {
            own_ids = ts.valid_ids;
            own_pool.reset(new NodePool());
            top.ids = own_ids.data();
            top.pool = own_pool.get();
        }
        // Chunks of rays traced independently. DACRT wants big batches: measured on 1M diffuse
        // rays x 100K triangles, 64K-ray chunks cost 2x the CPU time of one batch (each chunk
        // repeats the deeper partitioning and reaches brute-force leaves sooner), n/2 chunks 5%;
        // on 400K diffuse rays x 268K triangles, 2 threads, 4 chunks gave 4.5 Mrays/s and 2
        // chunks 5.7. So one chunk per thread. With a kept top (the frame's earlier batches
        // split it down to ~16-triangle nodes) a chunk repeats almost nothing, so a smaller
        // batch (shadow rays, deep bounces) is split too: on the dragon (100K triangles, 4 spp)
        // most batches have 1K-45K rays and ran on one thread.
        const size_t min_chunk = use_kept ? kMinKeptChunkRays : kMinChunkRays;
        auto chunks_of = [&](size_t m) {
            const size_t c = job.cfg.chunk_rays ? m / job.cfg.chunk_rays + (m % job.cfg.chunk_rays != 0)  // no overflow near 2^64
                                                : std::min(size_t(T), (m + min_chunk - 1) / min_chunk);
            return std::max<size_t>(1, c);
        };
        const size_t whole = chunks_of(n), chunk = (n + whole - 1) / whole;
        // The origin groups and, for each, the number of the chunks before its first (a chunk's
        // group found by a scan: groups are few, chunks may be one per ray).
        const std::vector<Span> groups = origin_groups(ts, rays, n, job.batch.origin_abs_max);
        std::vector<size_t> first_chunk{0};
        for (const Span& g : groups) first_chunk.push_back(first_chunk.back() + chunks_of(g.e - g.b));
        const size_t chunks = first_chunk.back();
        bool spatial = false;  // some chunks were cut at origins
        for (size_t g = 0; g < groups.size(); ++g)  // chunks of nearby origins (chunkorder.h)
            spatial |= order_by_origin(rays + groups[g].b, groups[g].e - groups[g].b, first_chunk[g + 1] - first_chunk[g]);
        if (size_t(T) > chunks) T = int(chunks);
        res.threads = T;

        // A call's own top stops at the balanced depth, below which each chunk's nodes follow
        // its own rays (few rays: a brute-force leaf instead of a split). A kept top goes on
        // down to every node of more than ~16 triangles that any batch reaches: its splits
        // are made once per frame, and on unevenly dense scenes the tree is far deeper than
        // balanced (bmw27, 1.7M triangles: leaves of thousands of triangles met by <= 32 rays
        // below the balanced depth, 100-800 triangle tests per ray).
        top.max_depth = use_kept ? kKeptMaxDepth : levels;
        // shared down to the leaf size, so a kept top leaves later batches no splits to redo
        top.min_tris = std::min<size_t>(kSharedMinTris / 2, size_t(job.cfg.leaf_size));
        top.ray_scale = float(n) / float(std::min(n, chunk));
        TraceJob jb = job;
        jb.top = &top;
        jb.num_ids = n;

        // Work stealing: a thread out of chunks takes a far child that another has yet to visit
        // (StealBoard, kernel.h), so chunks of unequal cost still finish together. Only where
        // the chunks were cut at origins: chunks of one origin's rays (a pinhole camera's) cut
        // by index cost alike, and stealing between them cost camera rays 4% more CPU time and
        // 6.5% more wall time.
        StealBoard board;  // working: threads that have joined and not yet finished (see worker)
        if (T > 1 && spatial) jb.steal = &board;
        TaskFn task_fn = isa == Isa::Avx512 ? avx512::trace_task : (isa == Isa::Avx2 ? avx2::trace_task : portable::trace_task);

        std::atomic<size_t> next{0};
        std::vector<Stats> stats(T);
        std::vector<std::exception_ptr> errors(T);
        // A thread counts as working from the moment it joins, not from the call's start: one
        // that a loaded machine has not scheduled yet holds nobody back. The others trace
        // every chunk and finish; run_workers then runs its index on whichever thread is free
        // (parallel.cpp), where it finds no chunk left. A thread that joins late takes the
        // chunks still left and is stolen from as any other.
        auto worker = [&](int w) {
            std::vector<uint32_t> ids;  // sized on the first chunk: a late index may find none
            {
                std::lock_guard<std::mutex> g(board.m);
                ++board.working;
            }
            try {
                for (;;) {
                    const size_t c = next.fetch_add(1);
                    if (c >= chunks) break;
                    if (ids.size() < nt) ids.resize(nt);
                    size_t g = 0;
                    while (c >= first_chunk[g + 1]) ++g;
                    const size_t m = groups[g].e - groups[g].b, k = c - first_chunk[g], cs = first_chunk[g + 1] - first_chunk[g];
                    const size_t b = groups[g].b + m * k / cs, e = groups[g].b + m * (k + 1) / cs;
                    TraceJob jc = jb;
                    jc.batch.origin_abs_max = groups[g].origin_abs_max;
                    jc.batch.far_origins = groups[g].far;
                    fn(jc, rays + b, e - b, ids.data(), stats[w]);
                }
            } catch (...) {  // e.g. out of memory: stop handing out chunks, rethrow on the caller
                errors[w] = std::current_exception();
                next.store(chunks);
            }
            // Then tasks, until no thread traces anything. Only the caller's thread polls an
            // interrupt; while it waits it keeps polling (every 5 ms), or a cancel could wait
            // for the longest chunk.
            std::unique_lock<std::mutex> lk(board.m);
            if (--board.working == 0) board.cv.notify_all();
            for (;;) {
                if (!board.queue.empty()) {
                    StolenTask* t = board.queue.front();
                    board.queue.pop_front();
                    --board.offered;
                    board.update();
                    ++board.working;
                    lk.unlock();
                    try {
                        if (ids.size() < nt) ids.resize(nt);
                        task_fn(jb, *t, ids.data(), stats[w]);
                    } catch (...) {
                        if (!errors[w]) errors[w] = std::current_exception();
                    }
                    lk.lock();
                    if (--board.working == 0) board.cv.notify_all();
                    continue;
                }
                if (board.working == 0) break;
                ++board.waiting;
                board.update();
                if (w == 0 && job.interrupt) {
                    board.cv.wait_for(lk, std::chrono::milliseconds(5));
                    lk.unlock();
                    try {
                        job.interrupt->stop();
                    } catch (...) {
                        if (!errors[0]) errors[0] = std::current_exception();
                    }
                    lk.lock();
                } else {
                    board.cv.wait(lk);
                }
                --board.waiting;
                board.update();
            }
        };
        run_workers(T, worker);
        for (auto& e : errors)
            if (e) std::rethrow_exception(e);
        if (job.interrupt && job.interrupt->raised()) throw Cancelled();
        if (!board.all.empty()) merge_stolen(board, job, n, T);
        for (const Stats& s : stats) res.stats.add(s);
        res.stats.rays = n;
        if (use_kept) {
            kept.unlock();
            res.order_seconds = store_in_top_order(ts, *cache);
        }
    }
    res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
}

}  // namespace dacrt
