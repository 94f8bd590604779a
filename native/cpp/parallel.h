// A minimal parallel loop for the per-ray helper kernels (shading side): splits [0, n) into one
// contiguous range per thread. Spawning threads per call costs ~50 us, negligible against the
// 10^5..10^6-element arrays these kernels see; small inputs run on the calling thread.
#pragma once

#include <algorithm>
#include <cstddef>
#include <thread>
#include <vector>

namespace dacrt {

template <class F>
void parallel_for(size_t n, F&& body, size_t min_per_thread = 1 << 15) {
    size_t hw = std::max<size_t>(1, std::thread::hardware_concurrency());
    size_t threads = std::min(hw, std::max<size_t>(1, n / min_per_thread));
    if (threads <= 1) {
        body(size_t(0), n);
        return;
    }
    std::vector<std::thread> pool;
    pool.reserve(threads - 1);
    const size_t step = (n + threads - 1) / threads;
    for (size_t t = 1; t < threads; ++t) {
        size_t b = std::min(n, t * step), e = std::min(n, b + step);
        pool.emplace_back([&body, b, e] { body(b, e); });
    }
    body(size_t(0), std::min(n, step));
    for (auto& th : pool) th.join();
}

}  // namespace dacrt
