// Threads kept between rounds of work (internal to the library).
//
// A vector environment steps its episodes a few hundred microseconds at a
// time; starting and joining a thread for each call costs tens of
// microseconds, a good part of that. Episodes keep a pool instead (a batch
// makes one for its call): between rounds its threads watch for the next
// one a little while (waking a thread that sleeps, on an idle CPU, costs
// tens of microseconds again), then sleep on a condition variable. A thread
// that has slept a millisecond or more can take as long again to get going,
// so a short round that comes that long after the last (the owner's own code
// ran in between: a trainer's policy, say) runs on the calling thread alone
// (kStillWarm and kWorthWaking in batch.cc). One round at a time (the
// owner's calls are serialised). A process forked from one
// whose pool had threads has none of them: the pool then leaves their
// bookkeeping behind, untouched, and starts afresh.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include <sys/types.h>

namespace simloop::detail {

class WorkerPool {
 public:
  WorkerPool() = default;
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Starts task(w) for w = 1 .. helpers on the pool's threads (starting any it
  // lacks) and returns how many run: fewer when no more threads can be had
  // (a process limit), none when the round is not worth waking them (above).
  // task must not throw.
  int start_round(int helpers, const std::function<void(int worker)>& task);
  // Returns once every task of the round has returned, calling `poll` at
  // least every 5 ms meanwhile.
  void wait_round(const std::function<void()>& poll);

 private:
  struct State {
    std::mutex mutex;  // to sleep on wake and done; the ticket changes under it
    std::condition_variable wake, done;
    std::vector<std::thread> threads;  // thread t is worker t + 1
    const std::function<void(int)>* task = nullptr;  // set before the ticket changes
    // The round (high 32 bits) and its helpers (low: workers 1 .. helpers
    // take part), published together.
    std::atomic<std::uint64_t> ticket{0};
    std::atomic<int> running{0};
    std::atomic<bool> stopping{false};
    pid_t process = 0;  // where the threads run
    // The last round, as the calling thread saw it: its start, its end, and
    // how many threads took part (the calling thread too).
    std::chrono::steady_clock::time_point started, ended;
    int taking_part = 0;
  };
  // Whether waking the threads for a round starting `now` pays (above).
  [[nodiscard]] bool worth_waking(std::chrono::steady_clock::time_point now) const;
  static void serve(State& state, int worker, std::uint64_t seen);
  std::unique_ptr<State> state_ = std::make_unique<State>();
};

}  // namespace simloop::detail
