// Stopping a trace call part-way: a renderer's Esc must not wait for a whole batch (one
// bounce of a million rays on a big scene takes seconds on a loaded machine). The caller gives
// a poll function; the thread that called the trace asks it between recursion steps, at most
// once per interval, and every worker stops at its next node once it has said stop. The call
// then throws Cancelled: its hits are incomplete and never returned.
#pragma once
#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <thread>

namespace dacrt {

struct Cancelled : std::exception {
    const char* what() const noexcept override { return "trace cancelled by its caller"; }
};

class Interrupt {
  public:
    // poll: true = stop; called only on the thread that constructs this (the caller's), which
    // must be the thread that then calls trace(). interval: seconds between polls (0: every
    // check, for tests).
    Interrupt(std::function<bool()> poll, double interval);

    // Whether the trace should stop now. On workers one relaxed load; on the caller's thread a
    // clock read every few calls and, when the interval has passed, the poll itself. An
    // exception from the poll stops every worker and propagates.
    bool stop() {
        if (raised_.load(std::memory_order_relaxed)) return true;
        return std::this_thread::get_id() == caller_ && poll_due();
    }
    bool raised() const { return raised_.load(std::memory_order_acquire); }

  private:
    bool poll_due();  // interrupt.cpp: compiled once, outside the per-ISA kernels

    std::atomic<bool> raised_{false};
    std::function<bool()> poll_;
    std::thread::id caller_;
    std::chrono::steady_clock::duration interval_;
    std::chrono::steady_clock::time_point next_;
    uint32_t calls_ = 0;  // the caller's checks since its last clock read
};

}  // namespace dacrt
