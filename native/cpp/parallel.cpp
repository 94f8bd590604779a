// The process-wide worker pool (see parallel.h).
//
// Workers park on a condition variable after a short spin: a renderer calls the next kernel
// within microseconds of the last, and a futex wake-up costs about as much as the spin. The
// pool is never destroyed (parked threads cost nothing at exit), and a forked child, which
// inherits the pool's memory but none of its threads, starts a new one.
#include "parallel.h"

#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <new>
#include <thread>
#include <vector>

namespace dacrt {

int hardware_threads() {
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof(set), &set) == 0) {
        const int c = CPU_COUNT(&set);
        if (c > 0) return c;
    }
    const unsigned h = std::thread::hardware_concurrency();
    return h ? int(h) : 1;
}

namespace {
// Per calling thread: a viewport's worker and an F12 render each keep their own (a process-wide
// limit, set by one and restored by the other in between, had stayed capped after both).
thread_local int t_thread_limit = 0;
}

void set_thread_limit(int limit) { t_thread_limit = std::max(0, limit); }

int thread_limit() { return t_thread_limit; }

int default_threads() {
    const int h = hardware_threads(), limit = thread_limit();
    return limit > 0 ? std::min(h, limit) : h;
}

int max_workers() {
    return std::max(hardware_threads(), int(std::thread::hardware_concurrency()));
}

namespace {

// Busy-waits up to ~50 us while waiting() holds: about the cost of a futex wake-up, so a
// worker catches the next kernel of a bounce without sleeping, and idles soon after.
template <class F>
void spin_while(F&& waiting) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(50);
    while (waiting()) {
        for (int i = 0; i < 32; ++i) {
#if defined(__x86_64__) || defined(__i386__)
            __builtin_ia32_pause();
#endif
        }
        if (std::chrono::steady_clock::now() > until) return;
    }
}

thread_local bool t_in_job = false;  // nested calls must not wait for the pool they run on

// A test's stand-in for a worker that a loaded machine has not scheduled yet: each wake-up
// sleeps this long (DACRT_TEST_WORKER_DELAY_US, microseconds) before the worker claims work.
long worker_delay_us() {
    static const long us = [] {
        const char* e = std::getenv("DACRT_TEST_WORKER_DELAY_US");
        return e ? std::max(0L, std::strtol(e, nullptr, 10)) : 0L;
    }();
    return us;
}

// Job indices are claimed, not assigned: a woken worker and, once job(0) returns, the caller
// take the call's indices 1..workers-1 from one counter, so a worker that has not run yet
// (a loaded machine: woken, not scheduled) never holds the call back: its index is run by
// whoever is free first, and the caller then waits only for indices that someone started. The
// counter shares a word with the call's generation, so a worker that woke for an earlier call
// cannot claim an index of a later one with the earlier call's job.
class Pool {
  public:
    // Runs job on workers 1..workers-1 of the pool and on the caller as 0.
    void run(int workers, const std::function<void(int)>& job) {
        uint32_t gen;
        {
            std::lock_guard<std::mutex> g(m_);
            while (int(threads_.size()) < workers - 1) {
                // a new worker has not seen this call's generation yet, whenever it starts
                const unsigned seen = generation_.load();
                threads_.emplace_back([this, seen] { loop(seen); });
                threads_.back().detach();
            }
            job_ = &job;
            active_ = workers;
            done_count_.store(0);
            errors_.assign(size_t(workers), nullptr);
            gen = generation_.load() + 1;
            claim_.store(uint64_t(gen) << 32 | 1u);
            generation_.store(gen, std::memory_order_release);
        }
        wake_.notify_all();
        call(0, job);
        std::unique_lock<std::mutex> lk(m_);
        // A worker that claims within kLateWorker is waited for, as all were before: the call
        // then ends with it awake, spinning for the next call. Returning at once instead (the
        // caller running every late index) left the worker out of step with back-to-back small
        // calls whenever other processes' threads took the cores: 4K-ray batches 1.4-2x wall.
        done_.wait_for(lk, kLateWorker, [&] {
            return done_count_.load() == workers - 1 || !unclaimed(gen, workers);
        });
        lk.unlock();
        for (int w; (w = claim(gen, workers)) >= 0;) {  // indices no worker has started yet
            call(w, job);
            done_count_.fetch_add(1);
        }
        lk.lock();
        done_.wait(lk, [&] { return done_count_.load() == workers - 1; });
        job_ = nullptr;
        for (auto& e : errors_)
            if (e) std::rethrow_exception(e);
    }

  private:
    static constexpr std::chrono::microseconds kLateWorker{1000};

    bool unclaimed(uint32_t gen, int workers) const {
        const uint64_t c = claim_.load();
        return uint32_t(c >> 32) == gen && int(uint32_t(c)) < workers;
    }

    // The next unclaimed index of call gen (of `workers`), or -1 when none is left or the call
    // is no longer gen.
    int claim(uint32_t gen, int workers) {
        uint64_t c = claim_.load();
        for (;;) {
            if (uint32_t(c >> 32) != gen || int(uint32_t(c)) >= workers) return -1;
            if (claim_.compare_exchange_weak(c, c + 1)) return int(uint32_t(c));
        }
    }

    void call(int w, const std::function<void(int)>& job) {
        t_in_job = true;
        try {
            job(w);
        } catch (...) {
            errors_[size_t(w)] = std::current_exception();
        }
        t_in_job = false;
    }

    void loop(unsigned seen) {
        for (;;) {
            spin_while([&] { return generation_.load(std::memory_order_acquire) == seen; });
            std::unique_lock<std::mutex> lk(m_);
            wake_.wait(lk, [&] { return generation_.load() != seen; });
            seen = generation_.load();
            const std::function<void(int)>* job = job_;  // null between calls (claims then fail)
            const int workers = active_;
            lk.unlock();
            if (worker_delay_us() > 0) std::this_thread::sleep_for(std::chrono::microseconds(worker_delay_us()));
            for (int w; (w = claim(seen, workers)) >= 0;) {
                call(w, *job);
                if (done_count_.fetch_add(1) + 1 == workers - 1) {
                    std::lock_guard<std::mutex> g(m_);  // the caller may be between check and wait
                    done_.notify_one();
                }
            }
        }
    }

    std::mutex m_;
    std::condition_variable wake_, done_;
    std::vector<std::thread> threads_;
    const std::function<void(int)>* job_ = nullptr;
    int active_ = 0;
    std::atomic<int> done_count_{0};         // indices 1.. finished, by workers or the caller
    std::atomic<uint32_t> generation_{0};
    std::atomic<uint64_t> claim_{0};         // generation << 32 | next index to claim
    std::vector<std::exception_ptr> errors_;
};

std::mutex g_owner;           // one call at a time uses the pool
Pool* g_pool = nullptr;       // created on first use, never destroyed

void forget_pool_in_child() {
    g_pool = nullptr;         // its threads do not exist in the child
    new (&g_owner) std::mutex();
}

void run_fresh(int workers, const std::function<void(int)>& job) {
    std::vector<std::exception_ptr> errors(static_cast<size_t>(workers));
    std::vector<std::thread> threads;
    for (int w = 1; w < workers; ++w)
        threads.emplace_back([&, w] {
            try {
                job(w);
            } catch (...) {
                errors[size_t(w)] = std::current_exception();
            }
        });
    try {
        job(0);
    } catch (...) {
        errors[0] = std::current_exception();
    }
    for (auto& t : threads) t.join();
    for (auto& e : errors)
        if (e) std::rethrow_exception(e);
}

}  // namespace

void run_workers(int workers, const std::function<void(int)>& job) {
    if (workers <= 1) {
        job(0);
        return;
    }
    std::unique_lock<std::mutex> own(g_owner, std::defer_lock);
    if (t_in_job || !own.try_lock()) {
        run_fresh(workers, job);
        return;
    }
    if (!g_pool) {
        static const bool registered = [] { return pthread_atfork(nullptr, nullptr, forget_pool_in_child) == 0; }();
        (void)registered;
        g_pool = new Pool();
    }
    g_pool->run(workers, job);
}

}  // namespace dacrt
