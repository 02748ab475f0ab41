// Threads kept between rounds of work (internal to the library).
//
// A vector environment steps its episodes a few hundred microseconds at a
// time; starting and joining a thread for each call costs tens of
// microseconds, a good part of that. Episodes keep a pool instead: between
// rounds its threads watch for the next one a little while (waking a thread
// that sleeps, on an idle CPU, costs tens of microseconds again), then sleep
// on a condition variable. One round at a time
// (the owner's calls are serialised). A process forked from one whose pool
// had threads has none of them: the pool then leaves their bookkeeping
// behind, untouched, and starts afresh.
#pragma once

#include <atomic>
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
  // (a process limit). task must not throw.
  int start_round(int helpers, const std::function<void(int worker)>& task);
  // Returns once every task of the round has returned, calling `poll` at
  // least every 5 ms meanwhile.
  void wait_round(const std::function<void()>& poll);

 private:
  struct State {
    std::mutex mutex;  // to sleep on wake and done; round only grows under it
    std::condition_variable wake, done;
    std::vector<std::thread> threads;  // thread t is worker t + 1
    const std::function<void(int)>* task = nullptr;  // set before round grows
    int helpers = 0;  // workers 1 .. helpers take part in this round
    std::atomic<std::uint64_t> round{0};
    std::atomic<int> running{0};
    std::atomic<bool> stopping{false};
    pid_t process = 0;  // where the threads run
  };
  static void serve(State& state, int worker);
  std::unique_ptr<State> state_ = std::make_unique<State>();
};

}  // namespace simloop::detail
