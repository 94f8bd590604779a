// The caller-side poll of an Interrupt (interrupt.h).
#include "interrupt.h"

namespace dacrt {

Interrupt::Interrupt(std::function<bool()> poll, double interval)
    : poll_(std::move(poll)),
      caller_(std::this_thread::get_id()),
      interval_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(interval > 0.0 ? interval : 0.0))),
      next_(std::chrono::steady_clock::now() + interval_) {}

bool Interrupt::poll_due() {
    // A node visit takes from ~100 ns (a few rays) to milliseconds (a top-level filter): the
    // clock (~20 ns) is read on every 16th check, so it costs nothing and misses little.
    if (interval_.count() > 0 && (++calls_ & 15u) != 0) return false;
    const auto now = std::chrono::steady_clock::now();
    if (now < next_) return false;
    next_ = now + interval_;
    bool stop = true;
    try {
        stop = poll_();
    } catch (...) {
        raised_.store(true, std::memory_order_release);  // the other workers stop too
        throw;
    }
    if (stop) raised_.store(true, std::memory_order_release);
    return stop;
}

}  // namespace dacrt
