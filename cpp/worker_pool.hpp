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
// as long as on one). On a busy machine that makes the calling thread step
// every job alone while the woken thread waits for a CPU; so once rounds
// take a millisecond or more of CPU, the calling thread hands all the jobs
// to the pool's threads and sleeps (EnvPool's shape): each worker is then a
// thread that competes for the CPU on its own (measured: bench_envpool.py,
// docs/performance.md). One round at a time (the owner's calls are
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
  // Withdraws the offers no thread has taken yet (withdraw = true: for a
  // caller whose own share of the work leaves none to the others), then
  // returns once every task taken has returned, calling `poll` at least
  // every 5 ms meanwhile.
  void wait_round(const std::function<void()>& poll, bool withdraw = true);

  // Whether the calling thread should only hand the next round out and
  // wait (see run_jobs): the rounds have been long, in CPU time. note_round
  // tells it a round's CPU time, every worker's together.
  [[nodiscard]] bool caller_waits() const noexcept { return caller_waits_; }
  void note_round(std::int64_t cpu_ns) noexcept;
  static void set_long_round_for_testing(std::int64_t cpu_ns) noexcept;

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
  bool caller_waits_ = false;
};

// This thread's CPU time so far, in ns.
std::int64_t thread_cpu_ns() noexcept;

}  // namespace simloop::detail
