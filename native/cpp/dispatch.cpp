// Run-time ISA dispatch and threading (see dispatch.h).
//
// Multithreading: independent ray chunks traced in parallel as in the paper (one per thread,
// handed out dynamically when chunk_rays asks for more), plus shared top levels (kernel.h
// SharedTop) so the threads do not repeat the large partitioning steps. Allocations
// of a call: the shared triangle id array, one id scratch per thread (4 bytes per triangle
// each) and the shared nodes (two per published split); nothing per ray.
#include "dispatch.h"
#include "parallel.h"

#include <atomic>
#include <chrono>
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

TraceResult trace(const TriangleSet& ts, Ray* rays, size_t n, const TraceJob& job_in, int threads, Isa isa,
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
        int T = threads > 0 ? std::min(threads, max_workers()) : hardware_threads();
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
        size_t chunks;
        if (job.cfg.chunk_rays) {
            chunks = n / job.cfg.chunk_rays + (n % job.cfg.chunk_rays != 0);  // no overflow near 2^64
        } else {
            chunks = std::min(size_t(T), (n + min_chunk - 1) / min_chunk);
        }
        chunks = std::max<size_t>(1, chunks);
        const size_t chunk = (n + chunks - 1) / chunks;
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

        std::atomic<size_t> next{0};
        std::vector<Stats> stats(T);
        std::vector<std::exception_ptr> errors(T);
        auto worker = [&](int w) {
            try {
                std::vector<uint32_t> ids(nt);
                for (;;) {
                    const size_t c = next.fetch_add(1);
                    if (c >= chunks) break;
                    const size_t b = n * c / chunks, e = n * (c + 1) / chunks;
                    fn(jb, rays + b, e - b, ids.data(), stats[w]);
                }
            } catch (...) {  // e.g. out of memory: stop handing out chunks, rethrow on the caller
                errors[w] = std::current_exception();
                next.store(chunks);
            }
        };
        run_workers(T, worker);
        for (auto& e : errors)
            if (e) std::rethrow_exception(e);
        for (const Stats& s : stats) res.stats.add(s);
        res.stats.rays = n;
    }
    res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
}

}  // namespace dacrt
