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

class Pool {
  public:
    // Runs job on workers 1..workers-1 of the pool and on the caller as 0.
    void run(int workers, const std::function<void(int)>& job) {
        {
            std::lock_guard<std::mutex> g(m_);
            while (int(threads_.size()) < workers - 1) {
                // a new worker has not seen this call's generation yet, whenever it starts
                const int w = int(threads_.size()) + 1;
                const unsigned seen = generation_.load();
                threads_.emplace_back([this, w, seen] { loop(w, seen); });
                threads_.back().detach();
            }
            job_ = &job;
            active_ = workers;
            pending_.store(workers - 1);
            errors_.assign(size_t(workers), nullptr);
            generation_.fetch_add(1, std::memory_order_release);
        }
        wake_.notify_all();
        call(0, job);
        std::unique_lock<std::mutex> lk(m_);
        done_.wait(lk, [this] { return pending_.load() == 0; });
        job_ = nullptr;
        for (auto& e : errors_)
            if (e) std::rethrow_exception(e);
    }

  private:
    void call(int w, const std::function<void(int)>& job) {
        t_in_job = true;
        try {
            job(w);
        } catch (...) {
            errors_[size_t(w)] = std::current_exception();
        }
        t_in_job = false;
    }

    void loop(int w, unsigned seen) {
        for (;;) {
            spin_while([&] { return generation_.load(std::memory_order_acquire) == seen; });
            std::unique_lock<std::mutex> lk(m_);
            wake_.wait(lk, [&] { return generation_.load() != seen; });
            seen = generation_.load();
            if (w >= active_) continue;  // this call needs fewer workers
            const std::function<void(int)>* job = job_;
            lk.unlock();
            call(w, *job);
            if (pending_.fetch_sub(1) == 1) {
                std::lock_guard<std::mutex> g(m_);  // the caller may be between check and wait
                done_.notify_one();
            }
        }
    }

    std::mutex m_;
    std::condition_variable wake_, done_;
    std::vector<std::thread> threads_;
    const std::function<void(int)>* job_ = nullptr;
    int active_ = 0;
    std::atomic<int> pending_{0};
    std::atomic<unsigned> generation_{0};
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
