// One call at a time into an object any thread may call (a Sim, Episodes),
// and waits that stay responsive: in slices, with the caller's check (the
// Python bindings run the signal handlers there) between them.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

namespace simloop {

// Calls wait_slice(slice) (it waits up to `slice` and says whether the wait
// is over) until it is over, calling between() after each slice that was
// not (between may throw: the wait ends with it). False if `timeout`
// seconds pass first.
bool wait_in_slices(const std::function<bool(std::chrono::milliseconds)>& wait_slice,
                    const std::function<void()>& between, std::optional<double> timeout = std::nullopt);

// Every call holds the gate for its whole length, so no call sees another
// half done (a step while set_timestep swaps the model, say).
class CallGate {
 public:
  using TryFor = std::function<bool(std::chrono::milliseconds)>;

  // Enters the gate. InvalidArgument naming `what` ("this Sim is") when this
  // thread is inside it already: a signal handler or progress callback, run
  // from inside a call, calling again is refused rather than deadlocked.
  // When another thread is inside, wait(try_for) waits: try_for(slice) waits
  // up to `slice` to enter and says whether it did (wait_in_slices around
  // it lets the waiter act on Ctrl-C). If wait throws, the gate is not
  // entered.
  template <class Wait>
  void enter(const char* what, Wait&& wait) {
    refuse_reentry(what);
    if (!mutex_.try_lock())
      wait(TryFor([this](std::chrono::milliseconds slice) { return mutex_.try_lock_for(slice); }));
    holder_.store(std::this_thread::get_id(), std::memory_order_relaxed);
  }
  void leave() noexcept {
    holder_.store(std::thread::id(), std::memory_order_relaxed);
    mutex_.unlock();
  }

 private:
  void refuse_reentry(const char* what) const;
  std::timed_mutex mutex_;
  // The thread inside, if any. Only it writes this, and a thread only asks
  // whether it is itself inside, so relaxed order does.
  std::atomic<std::thread::id> holder_{};
};

}  // namespace simloop
