// Stopping long work early, and watching it advance.
//
// The library's loops step in short chunks (RunControl::kChunkSteps). Between
// chunks, outside MuJoCo's C frames, they call advance(): it counts the
// progress, calls the caller's poll function (on the thread that made the
// control, at most every kPollInterval), and throws Interrupted once a stop
// was requested. request_stop() is a lock-free atomic store, so a signal
// handler or any thread may call it.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <thread>
#include <utility>

namespace simloop {

class RunControl {
 public:
  // poll(steps_done, steps_total): the Python bindings check for Ctrl-C
  // there; a progress bar draws there. It may call request_stop(), or throw:
  // the control then keeps what it threw and stops the work (see run()).
  using Poll = std::function<void(std::int64_t steps_done, std::int64_t steps_total)>;

  // Steps a loop runs between two calls to advance(). Small enough that a
  // stop takes effect within a few milliseconds on any scene the chapter's
  // size; the bookkeeping per chunk is a clock read and an atomic add.
  static constexpr std::int64_t kChunkSteps = 64;
  static constexpr std::chrono::milliseconds kPollInterval{20};

  RunControl() : owner_(std::this_thread::get_id()), last_poll_(std::chrono::steady_clock::now()) {}
  explicit RunControl(Poll poll) : RunControl() { poll_ = std::move(poll); }
  RunControl(const RunControl&) = delete;
  RunControl& operator=(const RunControl&) = delete;

  void request_stop() noexcept { stop_.store(true, std::memory_order_relaxed); }
  [[nodiscard]] bool stop_requested() const noexcept { return stop_.load(std::memory_order_relaxed); }

  // For the library's batches: one run failed (a policy raised, Ctrl-C
  // arrived inside it), so the runs still going stop at their next chunk
  // (advance() throws Interrupted) instead of running to their end, without
  // marking the control stopped for its owner. The batch clears it when its
  // workers are done.
  void abandon_batch(bool abandoned) noexcept { abandoned_.store(abandoned, std::memory_order_relaxed); }
  [[nodiscard]] bool batch_abandoned() const noexcept { return abandoned_.load(std::memory_order_relaxed); }

  // For the library's loops: announces `steps` more steps of work.
  void add_total(std::int64_t steps) noexcept { total_.fetch_add(steps, std::memory_order_relaxed); }
  // For the library's loops: `steps` more steps are done. Polls when due (on
  // the owner thread only) and throws Interrupted if a stop was requested.
  void advance(std::int64_t steps);
  // Polls now if on the owner thread (a batch's calling thread polls this way
  // while it waits for its workers), then throws Interrupted if stopped.
  void check();

  // Runs work(this) (long work that takes this control). When the work ends
  // with an exception because the poll threw (the loop's Interrupted, or a
  // batch's), what the poll threw is what the caller gets: the Ctrl-C the
  // user pressed, the progress callback's own error.
  template <class Work>
  auto run(Work&& work) -> decltype(work(this)) {
    try {
      return work(this);
    } catch (...) {
      if (poll_failure_) std::rethrow_exception(std::exchange(poll_failure_, nullptr));
      throw;
    }
  }

  [[nodiscard]] std::int64_t steps_done() const noexcept { return done_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::int64_t steps_total() const noexcept { return total_.load(std::memory_order_relaxed); }

 private:
  void poll_now();
  std::atomic<bool> stop_{false};
  std::atomic<bool> abandoned_{false};
  std::atomic<std::int64_t> done_{0};
  std::atomic<std::int64_t> total_{0};
  Poll poll_;
  std::exception_ptr poll_failure_;  // what the poll threw (owner thread only)
  std::thread::id owner_;
  std::chrono::steady_clock::time_point last_poll_;
};

static_assert(std::atomic<bool>::is_always_lock_free, "request_stop() must be async-signal-safe");

}  // namespace simloop
