// The Python-side holders of a Sim and of Episodes, shared by the bindings
// that step them (bindings_sim.cc) and that draw them (bindings_render.cc).
#pragma once

#include <pybind11/pybind11.h>

#include <atomic>
#include <cstddef>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "bindings_common.hpp"
#include "simloop/control.hpp"
#include "simloop/episode.hpp"
#include "simloop/model.hpp"
#include "simloop/scenario.hpp"
#include "simloop/sim.hpp"

namespace simloop_py {

namespace py = pybind11;

// What a Sim or Episodes holder shares so that any Python thread may call
// it. Every call holds the lock for its whole length, GIL released or not,
// so no call sees another half done (a step while set_timestep swaps the
// model, say). The lock is waited for without the GIL, so a thread waiting
// for it never blocks the thread that holds it from getting the GIL back;
// and in slices, between which the waiter runs Python's signal handlers, so
// Ctrl-C reaches a thread waiting for a call another thread is in for a
// long time.
struct Lockable {
  std::timed_mutex mutex;
  // The thread holding `mutex`, if any. Only the holder writes it, and a
  // thread only asks whether it is itself the holder, so relaxed order does.
  std::atomic<std::thread::id> holder{};
};

class CallLock {
 public:
  CallLock(Lockable& s, const char* what) : s_(s) {
    // A signal handler or a progress callback, run from inside this object's
    // own call, calling it again: refuse rather than deadlock.
    if (s.holder.load(std::memory_order_relaxed) == std::this_thread::get_id()) {
      throw py::value_error(std::string(what) +
                            " in the middle of a call on this thread (a signal handler or "
                            "progress callback called it); call it after that call returns");
    }
    if (!s.mutex.try_lock()) wait_in_slices([&](auto slice) { return s.mutex.try_lock_for(slice); });
    s.holder.store(std::this_thread::get_id(), std::memory_order_relaxed);
  }
  ~CallLock() {
    s_.holder.store(std::thread::id(), std::memory_order_relaxed);
    s_.mutex.unlock();
  }
  CallLock(const CallLock&) = delete;
  CallLock& operator=(const CallLock&) = delete;

 private:
  Lockable& s_;
};

struct PySim : Lockable {
  explicit PySim(const simloop::Model& model) : sim(model) {}
  explicit PySim(const simloop::Sim& other) : sim(other) {}
  simloop::Sim sim;
};

struct SimLock : CallLock {
  explicit SimLock(PySim& s) : CallLock(s, "this Sim is") {}
};

// Observations live in one (count, width) buffer the Python side reads
// after each call (copied out: a returned array never changes later).
struct PyEpisodes : Lockable {
  PyEpisodes(const simloop::Model& scene, const simloop::Scenario& scenario, const simloop::ScenarioConfig& config,
             std::size_t count)
      : episodes(scene, scenario, config, count),
        observations(static_cast<std::size_t>(episodes.width()) * count, 0.0) {}
  simloop::Episodes episodes;
  std::vector<double> observations;
};

struct EpisodesLock : CallLock {
  explicit EpisodesLock(PyEpisodes& e) : CallLock(e, "these episodes are") {}
};

}  // namespace simloop_py
