// The Python-side holders of a Sim and of Episodes, shared by the bindings
// that step them (bindings_sim.cc) and that draw them (bindings_render.cc).
#pragma once

#include <pybind11/pybind11.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "bindings_common.hpp"
#include "simloop/call_gate.hpp"
#include "simloop/control.hpp"
#include "simloop/episode.hpp"
#include "simloop/fields.hpp"
#include "simloop/model.hpp"
#include "simloop/scenario.hpp"
#include "simloop/sim.hpp"

namespace simloop_py {

namespace py = pybind11;

// What a Sim or Episodes holder shares so that any Python thread may call
// it: every call holds the gate for its whole length, GIL released or not.
// The gate is waited for without the GIL, so a thread waiting for it never
// blocks the thread inside from getting the GIL back.
struct Lockable {
  simloop::CallGate gate;
};

class CallLock {
 public:
  CallLock(Lockable& s, const char* what) : gate_(s.gate) {
    gate_.enter(what, [](const simloop::CallGate::TryFor& try_for) { wait_without_gil(try_for); });
  }
  ~CallLock() { gate_.leave(); }
  CallLock(const CallLock&) = delete;
  CallLock& operator=(const CallLock&) = delete;

 private:
  simloop::CallGate& gate_;
};

struct PySim : Lockable {
  explicit PySim(const simloop::Model& model) : sim(model) {}
  explicit PySim(const simloop::Sim& other) : sim(other) {}
  simloop::Sim sim;
};

struct SimLock : CallLock {
  explicit SimLock(PySim& s) : CallLock(s, "this Sim is") {}
};

// Sim.step's arguments as pybind11 takes them without a look from Python:
// a Python int (not a bool) an int64 holds, and None or a callable. Anything
// else is refused as pybind11 refuses a wrong type; simloop.Sim.step then
// converts it or names it in one line (simloop._checks).
struct StepCount {
  std::int64_t value = 0;
};
struct StepProgress {
  py::object callable;  // None or a callable
};

// Observations live in one (count, width) buffer the Python side reads
// after each call (copied out: a returned array never changes later).
struct PyEpisodes : Lockable {
  PyEpisodes(const simloop::Model& scene, const simloop::Scenario& scenario, const simloop::ScenarioConfig& config,
             std::size_t count, bool read_state = false)
      : episodes(scene, scenario, config, count, read_state),
        observations(static_cast<std::size_t>(episodes.width()) * count, 0.0) {}
  simloop::Episodes episodes;
  std::vector<double> observations;
};

struct EpisodesLock : CallLock {
  explicit EpisodesLock(PyEpisodes& e) : CallLock(e, "these episodes are") {}
};

// A numpy view of one of MuJoCo's arrays, kept alive by `owner` (a Sim,
// Episodes or model_owner); read-only unless `writable` (bindings_sim.cc).
py::array field_view(const simloop::FieldView& f, const py::object& owner, bool writable);
// What keeps a model's arrays alive: a holder of the model itself.
py::object model_owner(const simloop::Model& model);
// (rows_count, kind of object a row is or '') of a field: what named indexing reads.
py::tuple field_rows(const simloop::FieldView& f);
// A recorder row's step and time, ahead of what it observes.
constexpr std::size_t kRowLabels = 2;
// The episodes' views of their state (bindings_episode_state.cc).
void bind_episode_state(py::class_<PyEpisodes>& episodes);

}  // namespace simloop_py

namespace pybind11::detail {

template <>
struct type_caster<simloop_py::StepCount> {
  PYBIND11_TYPE_CASTER(simloop_py::StepCount, const_name("int"));
  bool load(handle src, bool /*convert*/) {
    if (!PyLong_CheckExact(src.ptr())) return false;
    int overflow = 0;
    value.value = PyLong_AsLongLongAndOverflow(src.ptr(), &overflow);
    return overflow == 0;
  }
};

template <>
struct type_caster<simloop_py::StepProgress> {
  PYBIND11_TYPE_CASTER(simloop_py::StepProgress, const_name("Optional[Callable[[int, int], None]]"));
  bool load(handle src, bool /*convert*/) {
    if (!src.is_none() && PyCallable_Check(src.ptr()) == 0) return false;
    value.callable = reinterpret_borrow<object>(src);
    return true;
  }
};

}  // namespace pybind11::detail
