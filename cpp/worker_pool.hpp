// Threads kept between rounds of work (internal to the library).
//
// A vector environment steps its episodes a few hundred microseconds at a
// time; starting and joining a thread for each call costs tens of
// microseconds, a good part of that. Episodes keep a pool instead (a batch
// makes one for its call): between rounds its threads watch for the next
// one a little while (waking a thread that sleeps, on an idle CPU, costs
// tens of microseconds again), then sleep on a condition variable. A round
// offers seats; a thread takes one as it wakes, and the calling thread, its
// own share done (the work is shared out job by job), closes the seats not
// yet taken: a thread that slept long (on a virtual machine that can take a
// millisecond, as long as a short round) then costs the round nothing but
// the wake-up call (on such a machine about 0.4 ms of the calling thread's
// time: after a pause, a round of 0.7 ms on two threads takes about 1.1 x
// as long as on one). One round at a time (the owner's calls are
// serialised). A process forked from one whose pool had threads has none of
// them: the pool then leaves their bookkeeping behind, untouched, and
// starts afresh.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace simloop::detail {

class WorkerPool {
 public:
  WorkerPool() = default;
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Offers task(w), w = 1 .. helpers, to the pool's threads (starting any it
  // lacks), each w to at most one, and returns how many are offered: fewer
  // when no more threads can be had (a process limit). task must not throw.
  int start_round(int helpers, const std::function<void(int worker)>& task);
  // Withdraws the offers no thread has taken yet, then returns once every
  // task taken has returned, calling `poll` at least every 5 ms meanwhile.
  // For a caller whose own share of the work leaves none to the others.
  void wait_round(const std::function<void()>& poll);

 private:
  struct State {
    std::mutex mutex;  // to sleep on wake and done; the ticket changes under it
    std::condition_variable wake, done;
    std::vector<std::thread> threads;
    const std::function<void(int)>* task = nullptr;  // set before the ticket changes
    // The round (high 32 bits) and its seats not yet taken (low: a thread
    // takes seat k, counting down, and is worker k), changed together.
    std::atomic<std::uint64_t> ticket{0};
    std::atomic<int> running{0};  // seats offered, less the tasks returned and the seats withdrawn
    std::atomic<bool> stopping{false};
    pid_t process = 0;  // where the threads run
  };
  static void serve(State& state, std::uint64_t seen_round);
  std::unique_ptr<State> state_ = std::make_unique<State>();
};

}  // namespace simloop::detail
