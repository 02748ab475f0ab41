#include "simloop/batch.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>

#include "run_detail.hpp"
#include "simloop/errors.hpp"
#include "worker_pool.hpp"

namespace simloop {

namespace {
// Tests only: threads the batch may still start (negative: no limit).
std::atomic<int> g_thread_starts_left{-1};

std::thread start_thread(const std::function<void()>& work) {
  int left = g_thread_starts_left.load();
  while (left >= 0) {
    if (left == 0) throw std::system_error(std::make_error_code(std::errc::resource_unavailable_try_again));
    if (g_thread_starts_left.compare_exchange_weak(left, left - 1)) break;
  }
  return std::thread(work);
}
}  // namespace

void detail::limit_thread_starts_for_testing(int threads) noexcept { g_thread_starts_left.store(threads); }

namespace {
// How long a pool's thread watches for the next round, and the calling
// thread for the round's end, before sleeping: about what a vector env's
// step of a few episodes takes.
constexpr std::chrono::microseconds kWatch{200};

// Watches `ready` for up to kWatch; true once it holds.
template <class Ready>
bool watch(Ready&& ready) {
  const auto until = std::chrono::steady_clock::now() + kWatch;
  while (!ready()) {
    if (std::chrono::steady_clock::now() >= until) return false;
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
  }
  return true;
}
}  // namespace

detail::WorkerPool::~WorkerPool() {
  State& s = *state_;
  if (s.threads.empty()) return;
  if (s.process != getpid()) {  // a forked child: the threads are the parent's (see start_round)
    static_cast<void>(state_.release());
    return;
  }
  {
    const std::lock_guard<std::mutex> lock(s.mutex);
    s.stopping.store(true);
  }
  s.wake.notify_all();
  for (std::thread& t : s.threads) t.join();
}

namespace {
constexpr std::uint64_t kSeats = 0xffffffffu;  // the ticket's low half
}  // namespace

void detail::WorkerPool::serve(State& s, std::uint64_t seen) {
  for (;;) {
    const auto next = [&] { return s.stopping.load() || s.ticket.load(std::memory_order_acquire) >> 32 != seen; };
    if (!watch(next)) {
      std::unique_lock<std::mutex> lock(s.mutex);
      s.wake.wait(lock, next);
    }
    if (s.stopping.load()) return;
    // A seat in this round, if one is left; its number is this thread's
    // worker number for the round. None left: the round's work is done.
    std::uint64_t ticket = s.ticket.load(std::memory_order_acquire);
    seen = ticket >> 32;
    while ((ticket & kSeats) != 0 && ticket >> 32 == seen &&
           !s.ticket.compare_exchange_weak(ticket, ticket - 1, std::memory_order_acq_rel, std::memory_order_acquire)) {
    }
    if (ticket >> 32 != seen || (ticket & kSeats) == 0) continue;
    (*s.task)(static_cast<int>(ticket & kSeats));
    if (s.running.fetch_sub(1, std::memory_order_acq_rel) == 1) {
      const std::lock_guard<std::mutex> lock(s.mutex);
      s.done.notify_all();
    }
  }
}

int detail::WorkerPool::start_round(int helpers, const std::function<void(int worker)>& task) {
  if (state_->process != getpid() && !state_->threads.empty()) {
    // Forked: the threads are the parent's. Their bookkeeping (its mutex
    // perhaps held at the fork) is left as it is, never used again.
    static_cast<void>(state_.release());
    state_ = std::make_unique<State>();
  }
  State& s = *state_;
  s.process = getpid();
  const std::uint64_t round = s.ticket.load() >> 32;
  s.threads.reserve(static_cast<std::size_t>(std::max(helpers, 0)));
  while (static_cast<int>(s.threads.size()) < helpers) {
    try {
      s.threads.push_back(start_thread([&s, round] { serve(s, round); }));
    } catch (const std::system_error&) {
      break;  // as many as could be had
    }
  }
  const int seats = std::min(helpers, static_cast<int>(s.threads.size()));
  s.task = &task;
  s.running.store(seats);
  {
    const std::lock_guard<std::mutex> lock(s.mutex);  // (a thread going to sleep sees it)
    s.ticket.store((round + 1) << 32 | static_cast<std::uint32_t>(seats), std::memory_order_release);
  }
  s.wake.notify_all();
  return seats;
}

void detail::WorkerPool::wait_round(const std::function<void()>& poll) {
  State& s = *state_;
  // The caller's own share is done, and with it every job: the seats no
  // thread has taken yet (it is still waking) close, and only the threads
  // at work are waited for.
  std::uint64_t ticket = s.ticket.load(std::memory_order_acquire);
  while ((ticket & kSeats) != 0 && !s.ticket.compare_exchange_weak(ticket, ticket & ~kSeats, std::memory_order_acq_rel,
                                                                   std::memory_order_acquire)) {
  }
  if ((ticket & kSeats) != 0) s.running.fetch_sub(static_cast<int>(ticket & kSeats), std::memory_order_acq_rel);
  const auto finished = [&] { return s.running.load(std::memory_order_acquire) == 0; };
  if (watch(finished)) return;
  std::unique_lock<std::mutex> lock(s.mutex);
  while (!s.done.wait_for(lock, std::chrono::milliseconds(5), finished)) {
    lock.unlock();
    poll();
    lock.lock();
  }
}

int batch_workers(int threads, std::size_t jobs) noexcept {
  const int wanted = threads > 0 ? threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  return static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(wanted), std::max<std::size_t>(jobs, 1)));
}

void detail::run_jobs(const Model& model, std::size_t jobs, int threads, const std::vector<std::int64_t>& steps,
                      RunControl* control,
                      const std::function<void(std::size_t job, Data& data, RunControl& control)>& job) {
  const int workers = batch_workers(threads, jobs);
  std::vector<Data> datas;
  datas.reserve(static_cast<std::size_t>(workers));
  for (int w = 0; w < workers; ++w) datas.emplace_back(model);
  run_jobs(jobs, threads, steps, control,
           [&](std::size_t i, int worker, RunControl& ctl) { job(i, datas[static_cast<std::size_t>(worker)], ctl); });
}

void detail::run_jobs(std::size_t jobs, int threads, const std::vector<std::int64_t>& steps, RunControl* control,
                      const std::function<void(std::size_t job, int worker, RunControl& control)>& job,
                      WorkerPool* kept) {
  const int workers = batch_workers(threads, jobs);
  RunControl own_control;
  RunControl& ctl = control ? *control : own_control;
  for (const std::int64_t s : steps) ctl.add_total(s);
  std::vector<std::exception_ptr> errors(jobs);
  // Workers stop taking jobs once any job failed or a stop was requested.
  std::atomic<std::size_t> next{0};
  const std::function<void(int)> work = [&](int worker) noexcept {
    for (std::size_t i; (i = next.fetch_add(1)) < jobs;) {
      try {
        job(i, worker, ctl);
      } catch (const Interrupted&) {
        // Stopped on request, or cut short because another run failed (then
        // that run's failure is the batch's, not this).
        if (ctl.stop_requested() || !ctl.batch_abandoned()) errors[i] = std::current_exception();
        next.store(jobs);
      } catch (...) {
        errors[i] = std::current_exception();
        next.store(jobs);
        // The runs still going stop at their next chunk rather than at their
        // end: a policy's exception (Ctrl-C inside it, say) acts at once.
        ctl.abandon_batch(true);
      }
    }
  };
  // The caller's kept threads, or threads for this call only (joined on
  // return). If fewer can be started than asked (a process limit), the ones
  // running share the work, which gives the same results.
  WorkerPool for_this_call;
  WorkerPool& pool = kept != nullptr ? *kept : for_this_call;
  if (workers > 1) pool.start_round(workers - 1, work);
  work(0);  // the calling thread is worker 0
  // Worker 0 is the control's thread: while the others finish, it keeps
  // polling, so a stop still takes effect promptly.
  pool.wait_round([&ctl] {
    try {
      ctl.check();
    } catch (const Interrupted&) {
      // Every worker sees the stop at its next chunk; wait for them.
    }
  });
  ctl.abandon_batch(false);
  if (ctl.stop_requested()) throw Interrupted("interrupted");
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace simloop
