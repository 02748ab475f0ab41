#include "simloop/batch.hpp"

#include <time.h>
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

void detail::WorkerPool::wait_round(const std::function<void()>& poll, bool withdraw) {
  State& s = *state_;
  // The caller's own share is done, and with it every job: the seats no
  // thread has taken yet (it is still waking) close, and only the threads
  // at work are waited for.
  std::uint64_t ticket = s.ticket.load(std::memory_order_acquire);
  while (
      withdraw && (ticket & kSeats) != 0 &&
      !s.ticket.compare_exchange_weak(ticket, ticket & ~kSeats, std::memory_order_acq_rel, std::memory_order_acquire)) {
  }
  if (withdraw && (ticket & kSeats) != 0) {
    s.running.fetch_sub(static_cast<int>(ticket & kSeats), std::memory_order_acq_rel);
  }
  const auto finished = [&] { return s.running.load(std::memory_order_acquire) == 0; };
  // (A caller that handed out the whole round sleeps at once: watching, it
  // would take a CPU from the workers.)
  if (withdraw ? watch(finished) : finished()) return;
  std::unique_lock<std::mutex> lock(s.mutex);
  while (!s.done.wait_for(lock, std::chrono::milliseconds(5), finished)) {
    lock.unlock();
    poll();
    lock.lock();
  }
}

namespace {
// A round this long in CPU time (every worker's) is long enough that the
// calling thread only hands it out; below half of it, it takes part again.
std::atomic<std::int64_t> g_long_round_ns{1'000'000};
}  // namespace

void detail::WorkerPool::set_long_round_for_testing(std::int64_t cpu_ns) noexcept { g_long_round_ns.store(cpu_ns); }

void detail::WorkerPool::note_round(std::int64_t cpu_ns) noexcept {
  const std::int64_t long_round = g_long_round_ns.load(std::memory_order_relaxed);
  caller_waits_ = caller_waits_ ? 2 * cpu_ns >= long_round : cpu_ns >= long_round;
}

std::int64_t detail::thread_cpu_ns() noexcept {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
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
  // The calling thread is the control's: while the workers finish, it keeps
  // polling, so a stop still takes effect promptly.
  const auto poll = [&ctl] {
    try {
      ctl.check();
    } catch (const Interrupted&) {
      // Every worker sees the stop at its next chunk; wait for them.
    }
  };
  // A kept pool's rounds are timed in CPU, each worker its own (a clock
  // read at each end of its part, not per job), for caller_waits.
  std::atomic<std::int64_t> round_cpu_ns{0};
  const bool timed = kept != nullptr && workers > 1;
  const std::function<void(int)> timed_work = [&](int worker) noexcept {
    const std::int64_t began = timed ? thread_cpu_ns() : 0;
    work(worker);
    if (timed) round_cpu_ns.fetch_add(thread_cpu_ns() - began, std::memory_order_relaxed);
  };
  const std::function<void(int)> seated = [&](int seat) noexcept { timed_work(seat - 1); };  // seat k: worker k - 1
  if (timed && pool.caller_waits()) {
    // Every job to the pool's threads; the calling thread sleeps meanwhile
    // (it does the work itself only if no thread can be had).
    if (pool.start_round(workers, seated) == 0) timed_work(0);
    pool.wait_round(poll, false);
  } else {
    if (workers > 1) pool.start_round(workers - 1, timed_work);
    timed_work(0);  // the calling thread is worker 0
    pool.wait_round(poll);
  }
  if (timed) pool.note_round(round_cpu_ns.load());
  ctl.abandon_batch(false);
  if (ctl.stop_requested()) throw Interrupted("interrupted");
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace simloop
