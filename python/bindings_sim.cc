// simloop._core's Sim (one run stepped from outside, safe from any thread,
// with views into its state) and Episodes (N runs stepped a decision at a
// time, under gym.py).
#include "bindings_sim.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "bindings_common.hpp"
#include "simloop/episode.hpp"
#include "simloop/fields.hpp"
#include "simloop/model.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"
#include "simloop/recorder.hpp"
#include "simloop/sim.hpp"

namespace simloop_py {
namespace {

using namespace pybind11::literals;

using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Part3 = std::optional<std::array<double, 3>>;  // a force or torque, or None

// fn(sim, args...) -- a Sim method or a function of a Sim -- as a Python
// method that holds the Sim's lock. Args: the Python arguments' types.
template <class... Args, class Fn>
auto locked(Fn fn) {
  return [fn](PySim& s, Args... args) {
    SimLock lock(s);
    return std::invoke(fn, s.sim, args...);
  };
}

// The same for an Episodes method.
template <class... Args, class Fn>
auto episodes_locked(Fn fn) {
  return [fn](PyEpisodes& e, Args... args) {
    EpisodesLock lock(e);
    return std::invoke(fn, e.episodes, args...);
  };
}

// Each episode's physics steps since its reset and sim time: (steps, times).
py::tuple progress_of(const simloop::Episodes& episodes) {
  const auto n = static_cast<py::ssize_t>(episodes.count());
  py::array_t<std::int64_t> steps(n);
  py::array_t<double> times(n);
  for (py::ssize_t i = 0; i < n; ++i) {
    steps.mutable_data()[i] = episodes.steps_taken(static_cast<std::size_t>(i));
    times.mutable_data()[i] = episodes.time(static_cast<std::size_t>(i));
  }
  return py::make_tuple(steps, times);
}

}  // namespace

// A numpy view of one of MuJoCo's arrays, of its element type, (rows, cols)
// or (rows,) when cols is 1, kept alive by `owner` through its base (safe:
// a Sim's mjData never moves, nor does a model the owner holds); read-only
// unless `writable`.
py::array field_view(const simloop::FieldView& f, const py::object& owner, bool writable) {
  py::dtype dtype;
  switch (f.element) {
    case simloop::Element::kFloat64:
      dtype = py::dtype::of<double>();
      break;
    case simloop::Element::kFloat32:
      dtype = py::dtype::of<float>();
      break;
    case simloop::Element::kInt32:
      dtype = py::dtype::of<std::int32_t>();
      break;
    case simloop::Element::kInt64:
      dtype = py::dtype::of<std::int64_t>();
      break;
    case simloop::Element::kUInt64:
      dtype = py::dtype::of<std::uint64_t>();
      break;
    case simloop::Element::kUInt8:
      dtype = py::dtype::of<std::uint8_t>();
      break;
    case simloop::Element::kInt8:
      dtype = py::dtype::of<std::int8_t>();
      break;
  }
  static double empty = 0.0;  // a size-0 view still needs a pointer
  void* at = f.data != nullptr && f.rows > 0 && f.cols > 0 ? f.data : &empty;
  const auto rows = static_cast<py::ssize_t>(f.rows), cols = static_cast<py::ssize_t>(f.cols);
  const py::ssize_t item = dtype.itemsize();
  py::array view = cols == 1 ? py::array(dtype, {rows}, {item}, at, owner)
                             : py::array(dtype, {rows, cols}, {item * cols, item}, at, owner);
  return writable ? view : read_only(view);
}

// What keeps a model's arrays alive: the model itself (a Sim may take a
// model of its own later; views of the one before stay valid).
py::object model_owner(const simloop::Model& model) {
  return py::capsule(new simloop::Model(model), [](void* p) { delete static_cast<simloop::Model*>(p); });
}

// (name, rows_count, rows_are) of a field: what named indexing reads.
py::tuple field_rows(const simloop::FieldView& f) {
  return py::make_tuple(f.rows_count, f.rows_are == mjOBJ_UNKNOWN ? std::string() : simloop::object_kind(f.rows_are));
}

void bind_sim(py::module_& m) {
  // Every call holds the Sim's lock (PySim, SimLock): safe from any thread.
  // The arrays (array()) are views into the Sim's mjData and take no lock:
  // see simloop.Sim's docstring for what that means across threads.
  py::class_<PySim>(m, "Sim")
      .def(py::init([](const simloop::Model& model) {
             return naming_failures("Sim", [&] { return std::make_unique<PySim>(model); });
           }),
           "model"_a)
      .def("copy", locked([](const simloop::Sim& sim) {
             return naming_failures("Sim.copy", [&] { return std::make_unique<PySim>(sim); });
           }),
           "An independent copy: its own data, the same (shared, read-only) model.")
      .def("reset", locked(&simloop::Sim::reset))
      .def("reset_to_keyframe", locked<int>(&simloop::Sim::reset_to_keyframe), "key"_a)
      .def("set_timestep", locked<double>(&simloop::Sim::set_timestep), "timestep"_a)
      .def_property_readonly("timestep", locked(&simloop::Sim::timestep))
      .def("set_ctrl", locked<double>(py::overload_cast<double>(&simloop::Sim::set_ctrl)), "value"_a)
      .def("set_ctrl_vector", locked<const Doubles&>([](auto& sim, const auto& values) {
             sim.set_ctrl(values.data(), static_cast<size_t>(values.size()));
           }),
           "values"_a)
      .def_property_readonly("ctrl", locked(&simloop::Sim::ctrl))
      .def("apply_wrench", locked<int, Part3, Part3>([](auto& sim, int body, const auto& force, const auto& torque) {
             sim.apply_wrench(body, force ? &*force : nullptr, torque ? &*torque : nullptr);
           }),
           "body"_a, "force"_a, "torque"_a)
      .def("clear_forces", locked(&simloop::Sim::clear_forces))
      .def("forward", locked(&simloop::Sim::forward))
      .def("get_state",
           locked<bool>([](auto& sim, bool mujoco) { return vector_array(mujoco ? sim.mujoco_state() : sim.state()); }),
           "mujoco"_a = false)
      .def("set_state", locked<const py::array_t<double, py::array::c_style>&>([](auto& sim, const auto& state) {
             sim.set_state(state.data(), static_cast<size_t>(state.size()));
           }),
           "state"_a)
      .def_property_readonly("state_layout", locked(&simloop::Sim::state_layout))
      // Names are looked up locked too: set_timestep may be swapping the model.
      .def("id", locked<const std::string&, const std::string&>([](auto& sim, const auto& kind, const auto& name) {
             return sim.id(simloop::object_type_of_kind(kind), name);
           }),
           "kind"_a, "name"_a)
      .def("checked_index", locked<const std::string&, long long>([](auto& sim, const auto& kind, long long index) {
             return sim.checked_index(simloop::object_type_of_kind(kind), index);
           }),
           "kind"_a, "index"_a)
      .def("body_velocity", locked<int>([](auto& sim, int body) { return vec(sim.body_velocity(body).data(), 6); }),
           "body"_a)
      .def_property_readonly("model", locked(&simloop::Sim::model), "This Sim's own model (with its timestep).")
      .def(
          "array",
          [](const py::object& self, const std::string& name) {
            PySim& s = self.cast<PySim&>();
            SimLock lock(s);  // for the model's sizes; the view itself outlives the lock, as documented
            const simloop::ArrayView a = s.sim.array(name);
            return field_view({a.data, simloop::Element::kFloat64, a.rows, std::max(a.width, 1)}, self, a.writable);
          },
          "name"_a, "A numpy view into this Sim's mjData (keeps the Sim alive).")
      .def(
          "data_field",
          [](const py::object& self, const std::string& name) {
            PySim& s = self.cast<PySim&>();
            SimLock lock(s);
            return field_view(s.sim.data_field(name), self, false);
          },
          "name"_a, "A read-only numpy view of any of mjData's arrays (keeps the Sim alive).")
      .def(
          "model_field",
          [](PySim& s, const std::string& name, bool writable) {
            SimLock lock(s);
            const simloop::FieldView f = writable ? s.sim.writable_model_field(name) : s.sim.model_field(name);
            return field_view(f, model_owner(s.sim.model()), writable);
          },
          "name"_a, "writable"_a,
          "A numpy view of any of mjModel's arrays: read-only, or writable (the parameters a trainer randomises; "
          "the Sim then has a model of its own).")
      .def(
          "field_rows",
          [](PySim& s, const std::string& owner, const std::string& name) {
            SimLock lock(s);
            return field_rows(owner == "model" ? s.sim.model_field(name) : s.sim.data_field(name));
          },
          "owner"_a, "name"_a, "(rows_count, kind of object a row is or '') of a model or data array.")
      .def("read",
           locked<const std::string&, long long, long long>([](auto& sim, const auto& name, auto start, auto count) {
             return vector_array(sim.read(name, start, count));
           }),
           "name"_a, "start"_a, "count"_a, "A copy of values start .. start+count-1 of array(name), flattened.")
      .def(
          "step",
          [](PySim& s, StepCount n, StepProgress progress) {
            SimLock lock(s);
            if (progress.callable.is_none() && n.value <= simloop::RunControl::kChunkSteps) {
              // One chunk: nothing to interrupt, so no RunControl to pay for
              // (Python checks for Ctrl-C between the calls of a tight loop).
              py::gil_scoped_release release;
              s.sim.step(n.value);  // which checks n
              return;
            }
            Interruptible work(std::move(progress.callable));
            work.run([&](simloop::RunControl* control) { s.sim.step(n.value, control); });
            work.finish();
          },
          "n"_a, "progress"_a = py::none())
      .def_static("check_steps", &simloop::Sim::check_steps, "n"_a, "What step() checks, checked alone.")
      .def_property_readonly("time", locked(&simloop::Sim::time))
      .def_property_readonly("steps_taken", locked(&simloop::Sim::steps_taken))
      .def_property_readonly("contacts", locked(&simloop::Sim::contacts))
      .def_property_readonly("warnings", locked(&simloop::Sim::warnings))
      // Pickled as its model (MuJoCo's binary, with this Sim's timestep), its
      // full state and its step count; MuJoCo's warnings are not carried.
      .def(py::pickle(
          [](PySim& s) {
            SimLock lock(s);
            return py::make_tuple(s.sim.model(), vector_array(s.sim.state()), s.sim.steps_taken());
          },
          [](const py::tuple& t) {
            if (t.size() != 3) throw py::value_error("cannot unpickle a Sim: expected (model, state, steps_taken)");
            auto s = std::make_unique<PySim>(t[0].cast<simloop::Model>());
            const auto state = t[1].cast<Doubles>();
            s->sim.set_state(state.data(), static_cast<size_t>(state.size()));
            s->sim.set_steps_taken(t[2].cast<std::int64_t>());
            return s;
          }));

  py::class_<PyEpisodes> episodes(m, "Episodes", "N episodes of a scenario, stepped a decision at a time (gym.py).");
  episodes
      .def(py::init([](const simloop::Model& scene, const simloop::Scenario& scenario,
                       const simloop::ScenarioConfig& config, std::size_t count, bool read_state) {
             return naming_failures(
                 "Episodes", [&] { return std::make_unique<PyEpisodes>(scene, scenario, config, count, read_state); });
           }),
           "scene"_a, "scenario"_a, "config"_a, "count"_a, "read_state"_a = false)
      // Fixed at construction: read without the lock.
      .def_property_readonly("count", [](PyEpisodes& e) { return e.episodes.count(); })
      .def_property_readonly("nu", [](PyEpisodes& e) { return e.episodes.nu(); })
      .def("read_data_at_step", episodes_locked<bool>(&simloop::Episodes::read_data_at_step), "on"_a)
      .def_property_readonly("steps", [](PyEpisodes& e) { return e.episodes.steps(); })
      .def_property_readonly("timestep", [](PyEpisodes& e) { return e.episodes.model().timestep(); })
      .def_property_readonly("column_names",
                             [](PyEpisodes& e) {
                               py::list names;
                               for (const simloop::Column& c : e.episodes.columns()) names.append(c.name);
                               return py::tuple(names);
                             })
      .def_property_readonly("ctrl_range",
                             [](PyEpisodes& e) {
                               const simloop::CtrlRange r = simloop::ctrl_range(e.episodes.model().get());
                               return py::make_tuple(vec(r.low.data(), r.low.size()),
                                                     vec(r.high.data(), r.high.size()));
                             })
      // reset and step return observations: the recorder's rows without their
      // step and time (the columns after them in column_names).
      .def(
          "reset",
          [](PyEpisodes& e, std::size_t i, std::uint64_t seed, const std::optional<std::string>& reset) {
            EpisodesLock lock(e);
            const auto width = static_cast<std::size_t>(e.episodes.width());
            if (i >= e.episodes.count()) {
              throw py::index_error("episode " + std::to_string(i) + " does not exist: there are " +
                                    std::to_string(e.episodes.count()));
            }
            // This episode's start: the keys its [reset] table names over the scenario's own.
            std::optional<simloop::ResetSpec> spec;
            if (reset) spec = simloop::reset_over(e.episodes.scenario().reset, *reset, "reset options");
            double* row = e.observations.data() + i * width;
            e.episodes.reset(i, seed, row, spec ? &*spec : nullptr);
            return vec(row + kRowLabels, width - kRowLabels);
          },
          "i"_a, "seed"_a, "reset"_a = py::none())
      .def(
          "step",
          [](PyEpisodes& e, const Doubles& actions, std::int64_t every,
             const std::optional<py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>>& active,
             int threads, bool progress) -> py::tuple {
            EpisodesLock lock(e);
            const std::size_t n = e.episodes.count();
            const auto width = static_cast<std::size_t>(e.episodes.width());
            py::array_t<bool> terminated(static_cast<py::ssize_t>(n)), truncated(static_cast<py::ssize_t>(n));
            static_assert(sizeof(bool) == sizeof(std::uint8_t), "numpy's bools are bytes");
            auto* term = reinterpret_cast<std::uint8_t*>(terminated.mutable_data());
            auto* trunc = reinterpret_cast<std::uint8_t*>(truncated.mutable_data());
            std::fill_n(term, n, 0);
            std::fill_n(trunc, n, 0);
            const std::uint8_t* mask = active ? active->data() : nullptr;
            const auto work_steps = every > 0 ? static_cast<double>(every) * static_cast<double>(n) : 0.0;
            const auto stepping = [&](simloop::RunControl* control) {
              e.episodes.step(actions.data(), static_cast<std::size_t>(actions.size()), every, mask,
                              active ? static_cast<std::size_t>(active->size()) : 0, e.observations.data(), term, trunc,
                              threads, control);
            };
            if (work_steps <= static_cast<double>(simloop::RunControl::kChunkSteps)) {
              py::gil_scoped_release release;  // nothing long to interrupt
              stepping(nullptr);
            } else {
              Interruptible work{py::none()};
              work.run(stepping);
            }
            py::array_t<double> observations(
                {static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(width - kRowLabels)});
            double* out = observations.mutable_data();
            for (std::size_t i = 0; i < n; ++i) {
              const double* row = e.observations.data() + i * width;
              out = std::copy(row + kRowLabels, row + width, out);
            }
            if (!progress) return py::make_tuple(observations, terminated, truncated);
            const py::tuple steps_times = progress_of(e.episodes);  // (the vector env's infos, in the same call)
            return py::make_tuple(observations, terminated, truncated, steps_times[0], steps_times[1]);
          },
          "actions"_a, "every"_a, "active"_a = py::none(), "threads"_a = 1, "progress"_a = false)
      .def("progress", episodes_locked(progress_of))
      .def("steps_taken", episodes_locked<std::size_t>(&simloop::Episodes::steps_taken), "i"_a)
      .def("time", episodes_locked<std::size_t>(&simloop::Episodes::time), "i"_a)
      .def("warnings", episodes_locked<std::size_t>(&simloop::Episodes::warnings), "i"_a);
  bind_episode_state(episodes);
}

}  // namespace simloop_py
