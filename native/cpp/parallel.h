// The threads every native pass runs on: one process-wide pool of parked workers, woken per
// call, instead of new std::threads per call. A renderer calls a dozen kernels per bounce and
// traces a few batches; creating, faulting in and joining fresh threads each time cost ~5% of a
// small render in kernel time (perf: clone, stack page faults, wake-ups).
#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>

namespace dacrt {

// Cores this process may run on (its CPU affinity), at least 1.
int hardware_threads();

// The calling thread's thread limit (0: none), set by a renderer that was told to use fewer
// cores (Blender's Render > Performance > Threads: Fixed): every kernel and the tracer's default
// called from that thread use at most this many threads. Results never depend on it.
void set_thread_limit(int limit);
int thread_limit();

// The threads a pass may use when its caller gives no count: hardware_threads(), capped by
// the thread limit.
int default_threads();

// The most workers a call asking for a thread count uses: the machine's hardware threads (at
// least hardware_threads()). Results never depend on the count, and every worker beyond it
// would only time-share a core and then stay parked in the pool for the life of the process.
int max_workers();

// Runs job(w) for w = 0..workers-1, w = 0 on the calling thread, and returns when all are done.
// An exception from any job is rethrown here (the first one). Calls from inside a job, or
// while another thread uses the pool, run on freshly created threads instead: never a deadlock.
void run_workers(int workers, const std::function<void(int)>& job);

// Threads worth using on n items of which each thread should get at least min_per_thread.
inline int threads_for(size_t n, size_t min_per_thread) {
    return int(std::min(size_t(default_threads()), std::max<size_t>(1, n / min_per_thread)));
}

// Splits [0, n) into one contiguous range per thread; small inputs run on the calling thread.
// max_threads > 0 caps the threads (a caller's own thread setting).
template <class F>
void parallel_for(size_t n, F&& body, size_t min_per_thread = 1 << 13, int max_threads = 0) {
    size_t threads = size_t(threads_for(n, min_per_thread));
    if (max_threads > 0) threads = std::min(threads, size_t(max_threads));
    if (threads <= 1) {
        body(size_t(0), n);
        return;
    }
    const size_t step = (n + threads - 1) / threads;
    run_workers(int(threads), [&](int w) {
        const size_t b = std::min(n, size_t(w) * step), e = std::min(n, b + step);
        if (b < e) body(b, e);
    });
}

}  // namespace dacrt
