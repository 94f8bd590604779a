// Run-time ISA dispatch and threading (see dispatch.h).
//
// Multithreading follows the paper: independent ray chunks traced in parallel, no
// synchronisation inside the recursion. Chunks are handed out dynamically (several per thread)
// so a chunk of cheap rays (sky) does not leave a core idle. Each thread owns one copy of the
// triangle id array (4 bytes per triangle), the only allocation of a trace call.
#include "dispatch.h"

#include <sched.h>

#include <atomic>
#include <chrono>
#include <exception>
#include <stdexcept>
#include <thread>

namespace dacrt {

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

int hardware_threads() {
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof(set), &set) == 0) {
        const int c = CPU_COUNT(&set);
        if (c > 0) return c;
    }
    const unsigned h = std::thread::hardware_concurrency();
    return h ? int(h) : 1;
}

TraceResult trace(const TriangleSet& ts, Ray* rays, size_t n, const TraceJob& job, int threads, Isa isa) {
    const auto t0 = std::chrono::steady_clock::now();
    TraceResult res;
    res.stats.rays = n;
    ChunkFn fn = isa == Isa::Avx512 ? avx512::trace_chunk : (isa == Isa::Avx2 ? avx2::trace_chunk : portable::trace_chunk);
    const size_t nt = ts.valid_ids.size();
    if (n > 0 && nt > 0) {
        int T = threads > 0 ? threads : hardware_threads();
        constexpr size_t kMinChunk = 16384;   // below this, repeated top-level partitioning dominates
        constexpr size_t kChunksPerThread = 4;
        size_t chunks = T > 1 ? std::min((n + kMinChunk - 1) / kMinChunk, size_t(T) * kChunksPerThread) : 1;
        if (chunks < 1) chunks = 1;
        if (size_t(T) > chunks) T = int(chunks);
        res.threads = T;
        std::atomic<size_t> next{0};
        std::vector<Stats> stats(T);
        std::vector<std::exception_ptr> errors(T);
        auto worker = [&](int w) {
            try {
                std::vector<uint32_t> ids(ts.valid_ids);
                for (;;) {
                    const size_t c = next.fetch_add(1);
                    if (c >= chunks) break;
                    const size_t b = n * c / chunks, e = n * (c + 1) / chunks;
                    fn(job, rays + b, e - b, ids.data(), stats[w]);
                }
            } catch (...) {  // e.g. out of memory: stop handing out chunks, rethrow on the caller
                errors[w] = std::current_exception();
                next.store(chunks);
            }
        };
        std::vector<std::thread> pool;
        for (int w = 1; w < T; ++w) pool.emplace_back(worker, w);
        worker(0);
        for (auto& th : pool) th.join();
        for (auto& e : errors)
            if (e) std::rethrow_exception(e);
        for (const Stats& s : stats) res.stats.add(s);
        res.stats.rays = n;
    }
    res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
}

}  // namespace dacrt
