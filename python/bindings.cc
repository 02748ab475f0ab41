// simloop._core: glue between the C++ library and Python. No simulation logic
// lives here: arguments are converted, the GIL is released around the C++
// work, and results are handed back as numpy views or plain Python values.
// Argument checking with Python's words lives in python/simloop/_api.py.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstring>
#include <cstdint>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <string>
#include <system_error>
#include <thread>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "bindings_common.hpp"
#include "cli_options.hpp"
#include "warning_counter.hpp"
#include "simloop/batch.hpp"
#include "simloop/control.hpp"
#include "simloop/episode.hpp"
#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/number_format.hpp"
#include "simloop/output.hpp"
#include "simloop/recorder.hpp"
#include "simloop/run.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/scene_params.hpp"
#include "simloop/scene_geometry.hpp"
#include "simloop/sim.hpp"
#include "simloop/sweep.hpp"
#include "simloop/version.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

using simloop_py::Interruptible;
using simloop_py::naming_failures;
using simloop_py::OutOfMemory;
using simloop_py::ResourceFailure;
using simloop_py::RowsToPython;

using simloop::RunResult;
using simloop::Trajectory;

py::dict metrics_dict(const simloop::Metrics& m) {
  py::dict d;
  d["box_final_pos"] = py::list(py::cast(std::vector<double>(m.box_final_pos.begin(), m.box_final_pos.end())));
  d["box_final_speed"] = m.box_final_speed;
  d["lateral_drift"] = m.lateral_drift;
  d["perturb"] = m.perturb;
  d["pusher_final_x"] = m.pusher_final_x;
  d["seed"] = m.seed;
  d["shove_moved_box"] = m.shove_moved_box;
  d["steps"] = m.steps;
  return d;
}

// The trajectory as a (rows, columns) read-only view of the result's own
// row-major buffer. No copy.
py::array trajectory_view(const py::object& owner, const Trajectory& t) {
  const auto rows = static_cast<py::ssize_t>(t.rows());
  py::array view(py::dtype::of<double>(), {rows, static_cast<py::ssize_t>(t.columns())},
                 {static_cast<py::ssize_t>(sizeof(double)) * t.columns(),
                  static_cast<py::ssize_t>(sizeof(double))},
                 t.data(), owner);
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

py::array column_view(const py::object& owner, const Trajectory& t, int column) {
  py::array view(py::dtype::of<double>(), {static_cast<py::ssize_t>(t.rows())},
                 {static_cast<py::ssize_t>(sizeof(double)) * t.columns()}, t.data() + column, owner);
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

int column_index(const Trajectory& t, const std::string& name) {
  for (int c = 0; c < t.columns(); ++c) {
    if (Trajectory::kColumnNames[c] == name) return c;
  }
  throw py::key_error("no trajectory column named '" + name + "'; see result.column_names");
}

py::tuple column_names(int first, int end) {
  py::tuple names(static_cast<size_t>(end - first));
  for (int c = first; c < end; ++c) {
    names[static_cast<size_t>(c - first)] = py::str(std::string(Trajectory::kColumnNames[c]));
  }
  return names;
}

simloop::ShoveRng shove_rng(const std::string& name) {
  const std::optional<simloop::ShoveRng> rng = simloop::parse_rng(name);
  if (!rng) throw py::value_error("rng must be 'mt19937_64' or 'numpy', got '" + name + "'");
  return *rng;
}

py::array vec(const double* values, size_t n) { return py::array_t<double>(static_cast<py::ssize_t>(n), values); }

// Text from the C++ side that may hold a path's raw bytes (not UTF-8): as a
// str the way Python decodes file names (os.fsdecode, surrogateescape).
py::str fs_str(const std::string& text) {
  PyObject* decoded = PyUnicode_DecodeFSDefaultAndSize(text.data(), static_cast<py::ssize_t>(text.size()));
  if (!decoded) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(decoded);
}

// Sets a Python error whose message is `what` on one line (MuJoCo's own
// messages can span several), decoded as fs_str does.
void set_error_fs(PyObject* type, const char* what) {
  std::string line;
  bool line_break = false;
  for (const char* c = what; *c; ++c) {
    if (*c == '\n' || *c == '\r') {
      line_break = true;
      continue;
    }
    if (line_break && !line.empty() && line.back() != ' ' && *c != ' ') line += ' ';
    line_break = false;
    line += *c;
  }
  PyObject* message = PyUnicode_DecodeFSDefaultAndSize(line.data(), static_cast<py::ssize_t>(line.size()));
  if (!message) {
    PyErr_Clear();
    PyErr_SetString(type, "(undecodable message)");
    return;
  }
  PyErr_SetObject(type, message);
  Py_DECREF(message);
}

std::string run_call(const char* name, const simloop::RunConfig& c) {
  return std::string(name) + "(steps=" + std::to_string(c.num_steps()) +
         ", record_every=" + std::to_string(c.record_every) + ")";
}

// A Sim that any Python thread may call. Every call holds the Sim's lock for
// its whole length, GIL released or not, so no call sees another half done
// (a step while set_timestep swaps the model, say). The lock is waited for
// without the GIL, so a thread waiting for it never blocks the thread that
// holds it from getting the GIL back; and in slices, between which the waiter
// runs Python's signal handlers, so Ctrl-C reaches a thread waiting for a Sim
// that another thread is stepping for a long time.
struct PySim {
  explicit PySim(const simloop::Model& model) : sim(model) {}
  explicit PySim(const simloop::Sim& other) : sim(other) {}
  simloop::Sim sim;
  std::timed_mutex mutex;
  // The thread holding `mutex`, if any. Only the holder writes it, and a
  // thread only asks whether it is itself the holder, so relaxed order does.
  std::atomic<std::thread::id> holder{};
};

class SimLock {
 public:
  explicit SimLock(PySim& s) : s_(s) {
    // A signal handler or a progress callback, run from inside this Sim's own
    // step, calling it again: refuse rather than deadlock.
    if (s.holder.load(std::memory_order_relaxed) == std::this_thread::get_id()) {
      throw py::value_error("this Sim is in the middle of a call on this thread (a signal handler or "
                            "progress callback called it); call it after that call returns");
    }
    while (!s.mutex.try_lock()) {
      bool locked = false;
      {
        py::gil_scoped_release release;
        locked = s.mutex.try_lock_for(simloop::RunControl::kPollInterval);
      }
      if (locked) break;
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
    s.holder.store(std::this_thread::get_id(), std::memory_order_relaxed);
  }
  ~SimLock() {
    s_.holder.store(std::thread::id(), std::memory_order_relaxed);
    s_.mutex.unlock();
  }
  SimLock(const SimLock&) = delete;
  SimLock& operator=(const SimLock&) = delete;

 private:
  PySim& s_;
};

// A Sim method as a Python method that holds the Sim's lock.
template <class R, class... Args>
auto locked(R (simloop::Sim::*fn)(Args...)) {
  return [fn](PySim& s, Args... args) -> R {
    SimLock lock(s);
    return (s.sim.*fn)(std::forward<Args>(args)...);
  };
}
template <class R, class... Args>
auto locked(R (simloop::Sim::*fn)(Args...) noexcept) {
  return [fn](PySim& s, Args... args) -> R {
    SimLock lock(s);
    return (s.sim.*fn)(std::forward<Args>(args)...);
  };
}
template <class R>
auto locked(R (simloop::Sim::*fn)() const) {
  return [fn](PySim& s) -> R {
    SimLock lock(s);
    return (s.sim.*fn)();
  };
}
template <class R>
auto locked(R (simloop::Sim::*fn)() const noexcept) {
  return [fn](PySim& s) -> R {
    SimLock lock(s);
    return (s.sim.*fn)();
  };
}


// --- Batches of the caller's own inputs, metrics-only batches, reprs ---

std::string py_bool(bool b) { return b ? "True" : "False"; }

std::string py_str_repr(const std::string& text) {
  return py::repr(py::str(text)).cast<std::string>();
}

// One RunInputs per run from Python's arrays (already checked and made
// C-contiguous float64 by simloop.scenario): controls (B, T, nu) gives run i
// its own slice, (T, nu) the same array to every run; initial_state (B, n)
// or (n,) likewise. The arrays are read in place: the caller keeps them
// alive (they are this call's arguments) for the whole call.
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::vector<simloop::RunInputs> run_inputs(std::size_t runs, const std::optional<DoubleArray>& controls,
                                           const std::optional<DoubleArray>& initial_state) {
  std::vector<simloop::RunInputs> out(runs);
  if (controls) {
    const py::ssize_t nd = controls->ndim();
    if (nd != 2 && nd != 3) throw py::value_error("controls must be (steps, nu) or (runs, steps, nu)");
    if (nd == 3 && static_cast<std::size_t>(controls->shape(0)) != runs) {
      throw py::value_error("controls: " + std::to_string(controls->shape(0)) + " runs' controls for " +
                            std::to_string(runs) + " runs");
    }
    const std::int64_t steps = controls->shape(nd - 2), width = controls->shape(nd - 1);
    for (std::size_t i = 0; i < runs; ++i) {
      out[i].controls = controls->data() + (nd == 3 ? i * static_cast<std::size_t>(steps * width) : 0);
      out[i].control_steps = steps;
      out[i].control_width = width;
    }
  }
  if (initial_state) {
    const py::ssize_t nd = initial_state->ndim();
    if (nd != 1 && nd != 2) throw py::value_error("initial_state must be (state_size,) or (runs, state_size)");
    if (nd == 2 && static_cast<std::size_t>(initial_state->shape(0)) != runs) {
      throw py::value_error("initial_state: " + std::to_string(initial_state->shape(0)) + " states for " +
                            std::to_string(runs) + " runs");
    }
    const auto size = static_cast<std::size_t>(initial_state->shape(nd - 1));
    for (std::size_t i = 0; i < runs; ++i) {
      out[i].initial_state = initial_state->data() + (nd == 2 ? i * size : 0);
      out[i].state_size = size;
    }
  }
  return out;
}

py::array vector_array(const std::vector<double>& values) { return vec(values.data(), values.size()); }

// --- Sim for any scene: views into mjData and mjModel, names, pickling.

// A numpy view of `count` (x `width`) doubles at `values`, owned by `owner`
// (the Sim or Model Python object), which the view keeps alive through its
// base. Safe because a Sim's mjData and a Model's mjModel never move.
py::array owned_view(const py::object& owner, double* values, py::ssize_t count, py::ssize_t width, bool writable) {
  static double empty = 0.0;  // a size-0 view still needs a pointer to own nothing
  double* at = count > 0 ? values : &empty;
  const auto item = static_cast<py::ssize_t>(sizeof(double));
  py::array view = width > 0 ? py::array(py::dtype::of<double>(), {count, width}, {item * width, item}, at, owner)
                             : py::array(py::dtype::of<double>(), {count}, {item}, at, owner);
  if (!writable) py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

mjtObj object_type(const std::string& kind) {
  if (kind == "body") return mjOBJ_BODY;
  if (kind == "joint") return mjOBJ_JOINT;
  if (kind == "actuator") return mjOBJ_ACTUATOR;
  if (kind == "sensor") return mjOBJ_SENSOR;
  if (kind == "keyframe") return mjOBJ_KEY;
  throw py::value_error("kind must be 'body', 'joint', 'actuator', 'sensor' or 'keyframe', got '" + kind + "'");
}

py::list model_names(const simloop::Model& model, const std::string& kind) {
  const mjtObj type = object_type(kind);
  const mjModel* raw = model.get();
  const int count = type == mjOBJ_BODY       ? raw->nbody
                    : type == mjOBJ_JOINT    ? raw->njnt
                    : type == mjOBJ_ACTUATOR ? raw->nu
                    : type == mjOBJ_SENSOR   ? raw->nsensor
                                             : raw->nkey;
  py::list names;
  for (int i = 0; i < count; ++i) {
    const char* name = mj_id2name(raw, type, i);
    names.append(py::str(name ? name : ""));
  }
  return names;
}

// A result's fields, in order, as bytes (pickling): plain values copied as
// they are, so every double comes back with the same bits. One list of
// fields per result (run_result_fields, scenario_result_fields) serves both
// directions: FieldWriter's field() appends, FieldReader's reads back.
class FieldWriter {
 public:
  template <class T>
  void field(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof value);
  }
  template <class T>
  void field(const std::vector<T>& values) {
    field(static_cast<std::uint64_t>(values.size()));
    if constexpr (std::is_trivially_copyable_v<T>) {
      bytes_.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
    } else {
      for (const T& v : values) field(v);
    }
  }
  void field(const std::string& text) {
    field(static_cast<std::uint64_t>(text.size()));
    bytes_ += text;
  }
  void field(const Trajectory& t) {
    field(t.rows());
    field(t.columns());
    bytes_.append(reinterpret_cast<const char*>(t.data()),
                  static_cast<size_t>(t.rows()) * static_cast<size_t>(t.columns()) * sizeof(double));
  }
  void field(const simloop::Warning& w) { warning_fields(*this, w); }
  void field(const simloop::Column& c) { column_fields(*this, c); }
  [[nodiscard]] py::bytes bytes() const { return py::bytes(bytes_); }

  template <class Io, class W>
  static void warning_fields(Io& io, W& w) {
    io.field(w.name);
    io.field(w.count);
    io.field(w.first_step);
    io.field(w.message);
  }
  template <class Io, class C>
  static void column_fields(Io& io, C& c) {
    io.field(c.name);
    io.field(c.unit);
    io.field(c.integer);
    io.field(c.input);
  }

 private:
  std::string bytes_;
};

class FieldReader {
 public:
  FieldReader(std::string bytes, const char* what) : bytes_(std::move(bytes)), what_(what) {}
  template <class T>
  void field(T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    std::memcpy(&value, take(sizeof value), sizeof value);
  }
  template <class T>
  void field(std::vector<T>& values) {
    if constexpr (std::is_trivially_copyable_v<T>) {
      values.resize(count(sizeof(T)));
      const size_t n = values.size() * sizeof(T);
      if (n > 0) std::memcpy(static_cast<void*>(values.data()), take(n), n);
    } else {
      values.resize(count(sizeof(std::uint64_t)));  // each element holds at least one count
      for (T& v : values) field(v);
    }
  }
  void field(std::string& text) {
    const size_t n = count(1);
    text.assign(take(n), n);
  }
  void field(Trajectory& t) {
    std::int64_t rows = 0;
    int columns = 0;
    field(rows);
    field(columns);
    if (rows < 0 || columns < 0 || (columns > 0 && static_cast<std::uint64_t>(rows) > left() / sizeof(double) /
                                                       static_cast<std::uint64_t>(columns))) {
      fail();
    }
    t = Trajectory(rows, columns);
    const size_t n = static_cast<size_t>(rows) * static_cast<size_t>(columns) * sizeof(double);
    if (n > 0) std::memcpy(t.mutable_row(0), take(n), n);
  }
  void field(simloop::Warning& w) { FieldWriter::warning_fields(*this, w); }
  void field(simloop::Column& c) { FieldWriter::column_fields(*this, c); }
  void finish() const {
    if (at_ != bytes_.size()) fail();
  }

 private:
  [[nodiscard]] std::uint64_t left() const noexcept { return bytes_.size() - at_; }
  // A stored element count, checked against the bytes left (each element
  // takes at least `min_size` bytes), so bad bytes cannot ask for huge memory.
  size_t count(size_t min_size) {
    std::uint64_t n = 0;
    field(n);
    if (n > left() / min_size) fail();
    return static_cast<size_t>(n);
  }
  const char* take(size_t n) {
    if (n > left()) fail();
    const char* at = bytes_.data() + at_;
    at_ += n;
    return at;
  }
  [[noreturn]] void fail() const {
    throw py::value_error(std::string("cannot unpickle a ") + what_ + ": the saved fields are damaged or from another "
                          "simloop version");
  }
  std::string bytes_;
  const char* what_;
  size_t at_ = 0;
};

// The pickle format's version: bump when a result's fields change.
constexpr int kPickleVersion = 1;

template <class Io, class Result>
void run_result_fields(Io& io, Result& r) {
  io.field(r.config.seed);
  io.field(r.config.steps);
  io.field(r.config.timestep);
  io.field(r.config.perturb);
  io.field(r.config.smoke);
  io.field(r.config.record_every);
  io.field(r.config.audit_energy);
  io.field(r.config.rng);
  io.field(r.metrics);
  io.field(r.unrounded_metrics);
  io.field(r.shove);
  io.field(r.trajectory);
  io.field(r.rows);
  io.field(r.warnings);
  io.field(r.energy);
  io.field(r.timestep);
  io.field(r.sim_time);
}

template <class Io, class Result>
void scenario_result_fields(Io& io, Result& r) {
  io.field(r.name);
  io.field(r.seed);
  io.field(r.rng);
  io.field(r.perturb);
  io.field(r.disturbed_bodies);
  io.field(r.columns);
  io.field(r.final_row);
  io.field(r.final_state);
  io.field(r.trajectory);
  io.field(r.rows);
  io.field(r.schedule.steps);
  io.field(r.schedule.control_changes);
  io.field(r.schedule.forces);
  io.field(r.warnings);
  io.field(r.timestep);
  io.field(r.sim_time);
}

template <class Result, void (*Fields)(FieldWriter&, const Result&)>
py::tuple pickle_fields(const Result& r) {
  FieldWriter out;
  Fields(out, r);
  return py::make_tuple(kPickleVersion, out.bytes());
}

template <class Result, void (*Fields)(FieldReader&, Result&)>
Result unpickle_fields(const py::tuple& t, const char* what) {
  if (t.size() != 2 || t[0].cast<int>() != kPickleVersion) {
    throw py::value_error(std::string("cannot unpickle a ") + what + " pickled by another simloop version");
  }
  FieldReader in(t[1].cast<std::string>(), what);
  Result r;
  Fields(in, r);
  in.finish();
  return r;
}

// A Python callable as the loop's Policy: decide(step, row) -> ctrl, where
// row is the recorder's row (a fresh float64 array) and ctrl an array of nu
// float64 (simloop/scenario.py's wrapper checks what the user's policy
// returned and adds the decision step to its exceptions). Called from
// whichever thread steps the run: it takes the GIL for the call only.
class PyPolicy final : public simloop::Policy {
 public:
  PyPolicy(py::object decide, std::int64_t every) : Policy(every), decide_(std::move(decide)) {}
  ~PyPolicy() override {
    py::gil_scoped_acquire gil;
    decide_ = py::object();
  }
  PyPolicy(const PyPolicy&) = delete;
  PyPolicy& operator=(const PyPolicy&) = delete;

  void decide(std::int64_t step, const double* observation, int width, double* ctrl, int nu) override {
    py::gil_scoped_acquire gil;
    const py::array_t<double> row(width, observation);
    const py::array_t<double, py::array::c_style | py::array::forcecast> out(decide_(step, row));
    if (out.size() != nu) {
      throw simloop::InvalidArgument("policy at decision step " + std::to_string(step) + ": " +
                                     std::to_string(out.size()) + " ctrl values for " + std::to_string(nu) + " actuators");
    }
    std::copy(out.data(), out.data() + nu, ctrl);
  }

 private:
  py::object decide_;
};

}  // namespace

void bind_outputs(py::module_& m);  // bindings_outputs.cc

PYBIND11_MODULE(_core, m) {
  m.doc() = "simloop's compiled core: the chapter's MuJoCo loop in C++ (use the simloop package).";
  m.attr("__version__") = simloop::kVersion;
  m.attr("MUJOCO_VERSION") = simloop::mujoco_version();
  m.attr("PUSHER_SCENE_XML") = std::string(simloop::pusher_scene_xml());
  m.attr("COLUMN_NAMES") = column_names(0, Trajectory::kNumBaseColumns);
  m.attr("ENERGY_COLUMN_NAMES") = column_names(Trajectory::kNumBaseColumns, Trajectory::kNumColumns);
  m.attr("SMOKE_STEPS") = simloop::kSmokeSteps;
  m.attr("SHOVE_STEPS") = simloop::kShoveSteps;
  m.attr("MAX_STEPS") = simloop::kMaxSteps;
  m.attr("MAX_RECORD_EVERY") = simloop::kMaxRecordEvery;

  static py::exception<simloop::MujocoError> mujoco_error(m, "MujocoError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const simloop::MujocoError& e) {
      set_error_fs(mujoco_error.ptr(), e.what());
    } catch (const simloop::InvalidArgument& e) {
      set_error_fs(PyExc_ValueError, e.what());
    } catch (const simloop::IoError& e) {
      set_error_fs(PyExc_OSError, e.what());
    } catch (const simloop::Error& e) {
      set_error_fs(PyExc_RuntimeError, e.what());
    } catch (const OutOfMemory& e) {
      set_error_fs(PyExc_MemoryError, e.what());
    } catch (const ResourceFailure& e) {
      set_error_fs(PyExc_RuntimeError, e.what());
    }
  });

  py::class_<simloop::Model>(m, "Model", "A compiled MuJoCo world: read-only, shared by every run on it.")
      .def_static("pusher_scene", &simloop::Model::pusher_scene, "The chapter's scene.")
      .def_static(
          "from_xml_string",
          [](std::string_view xml, std::string_view source) {
            return naming_failures("Model.from_xml_string", [&] { return simloop::Model::from_xml_string(xml, source); });
          },
          "xml"_a, "source"_a = "<string>",
          "Compiles MJCF text; it needs a body 'box' on a free joint and an actuator 0 on a slide or "
          "hinge joint.")
      .def_static(
          "from_file",
          [](const std::filesystem::path& path) {
            return naming_failures("Model.from_file(" + path.string() + ")",
                                   [&] { return simloop::Model::from_file(path.string()); });
          },
          "path"_a, "Compiles an MJCF file.")
      .def_static(
          "_copy_of_address",
          [](std::uintptr_t address, std::string_view source) {
            // simloop.load_model checked that the address is a mujoco.MjModel's
            // of this very libmujoco (simloop/_mujoco_check.py).
            return simloop::Model::copy_of(reinterpret_cast<const mjModel*>(address), source);
          },
          "address"_a, "source"_a, "A copy of the mjModel at `address` (a mujoco.MjModel's _address).")
      .def("with_timestep", &simloop::Model::with_timestep, "timestep"_a, "A copy with opt.timestep set.")
      .def_property_readonly("timestep", &simloop::Model::timestep)
      .def_property_readonly("nq", [](const simloop::Model& model) { return model.get()->nq; })
      .def_property_readonly("nv", [](const simloop::Model& model) { return model.get()->nv; })
      .def_property_readonly("nu", [](const simloop::Model& model) { return model.get()->nu; })
      .def("__repr__", [](const simloop::Model& model) {
        const mjModel* raw = model.get();
        const std::string name = model.name();
        return "<simloop.Model " + (name.empty() ? std::string("(unnamed)") : "'" + name + "'") +
               " nq=" + std::to_string(raw->nq) + " nv=" + std::to_string(raw->nv) + " nu=" + std::to_string(raw->nu) +
               " nbody=" + std::to_string(raw->nbody) + " timestep=" + simloop::python_float_repr(model.timestep()) +
               ">";
      });

  py::class_<simloop::RunConfig>(m, "RunConfig")
      .def(py::init([](std::uint64_t seed, std::int64_t steps, double timestep, bool perturb, bool smoke,
                       std::int64_t record_every, bool audit_energy, const std::string& rng) {
             return simloop::RunConfig{seed, steps, timestep, perturb, smoke, record_every, audit_energy,
                                       shove_rng(rng)};
           }),
           "seed"_a, "steps"_a, "timestep"_a, "perturb"_a, "smoke"_a, "record_every"_a, "audit_energy"_a = false,
           "rng"_a = "mt19937_64")
      .def_property_readonly("rng", [](const simloop::RunConfig& c) { return std::string(simloop::rng_name(c.rng)); })
      .def_readonly("audit_energy", &simloop::RunConfig::audit_energy)
      .def_readonly("seed", &simloop::RunConfig::seed)
      .def_readonly("steps", &simloop::RunConfig::steps)
      .def_readonly("timestep", &simloop::RunConfig::timestep)
      .def_readonly("perturb", &simloop::RunConfig::perturb)
      .def_readonly("smoke", &simloop::RunConfig::smoke)
      .def_readonly("record_every", &simloop::RunConfig::record_every);

  py::class_<simloop::Shove>(m, "Shove", "The sideways shove drawn for a run (applied only if perturb).")
      .def_readonly("newtons", &simloop::Shove::newtons)
      .def_readonly("sign", &simloop::Shove::sign)
      .def_readonly("start_step", &simloop::Shove::start_step)
      .def_readonly("steps", &simloop::Shove::num_steps)
      .def_property_readonly("force_y", &simloop::Shove::force_y)
      .def_property_readonly("rng", [](const simloop::Shove& s) { return std::string(simloop::rng_name(s.rng)); },
                             "The generator that drew it: 'mt19937_64' or 'numpy'.")
      .def("__repr__", [](const simloop::Shove& s) {
        return "Shove(newtons=" + simloop::python_float_repr(s.newtons) + ", sign=" +
               simloop::python_float_repr(s.sign) + ", start_step=" + std::to_string(s.start_step) +
               ", steps=" + std::to_string(s.num_steps) + ", rng='" + std::string(simloop::rng_name(s.rng)) + "')";
      });
  m.def(
      "draw_shove",
      [](std::uint64_t seed, std::int64_t steps, const std::string& rng) {
        return simloop::draw_shove(seed, steps, shove_rng(rng));
      },
      "seed"_a, "steps"_a = 2000, "rng"_a = "mt19937_64", "The shove a run of `steps` steps draws from `seed`.");

  py::class_<simloop::Warning>(m, "MujocoWarning", "A warning MuJoCo raised while stepping.")
      .def_readonly("name", &simloop::Warning::name)
      .def_readonly("count", &simloop::Warning::count)
      .def_readonly("first_step", &simloop::Warning::first_step)
      .def_readonly("message", &simloop::Warning::message)
      .def("__repr__", [](const simloop::Warning& w) {
        return "MujocoWarning(" + w.name + ", count=" + std::to_string(w.count) +
               ", first_step=" + std::to_string(w.first_step) + ")";
      });

  py::class_<RunResult>(m, "RunResult", "What one run did: metrics, trajectory, shove, warnings.")
      .def_property_readonly("metrics", [](const RunResult& r) { return metrics_dict(r.metrics); },
                             "The dict metrics.json holds (floats rounded to 6 decimals).")
      .def_property_readonly("trajectory", [](const py::object& self) { return trajectory_view(self, self.cast<const RunResult&>().trajectory); },
                             "(rows, columns) read-only float64 view; columns as in COLUMN_NAMES.")
      .def(
          "column",
          [](const py::object& self, const std::string& name) {
            const Trajectory& t = self.cast<const RunResult&>().trajectory;
            return column_view(self, t, column_index(t, name));
          },
          "name"_a, "One trajectory column as a read-only (strided) view (no copy).")
      .def_property_readonly(
          "columns",
          [](const py::object& self) {
            py::dict columns;
            for (int c = 0; c < self.cast<const RunResult&>().trajectory.columns(); ++c) {
              columns[py::str(std::string(Trajectory::kColumnNames[c]))] =
                  column_view(self, self.cast<const RunResult&>().trajectory, c);
            }
            return columns;
          },
          "Every trajectory column by name, as read-only views (no copy).")
      .def_property_readonly(
          "column_names",
          [](const RunResult& r) { return column_names(0, r.trajectory.columns()); },
          "This result's trajectory columns (COLUMN_NAMES, then ENERGY_COLUMN_NAMES with the audit).")
      .def_property_readonly(
          "energy",
          [](const RunResult& r) -> py::object {
            if (!r.config.audit_energy) return py::none();
            const simloop::EnergyTotals& e = r.energy;
            py::dict d;
            d["energy_start"] = e.energy_start;
            d["energy_end"] = e.energy_end;
            d["work_actuator"] = e.work_actuator;
            d["work_shove"] = e.work_shove;
            d["work_passive"] = e.work_passive;
            d["work_constraint"] = e.work_constraint;
            d["work_constraint_positive"] = e.work_constraint_positive;
            d["unexplained"] = e.unexplained;
            return std::move(d);
          },
          "The energy audit's totals, J (None unless audit_energy).")
      .def_property_readonly("rows", [](const RunResult& r) { return std::max(r.trajectory.rows(), r.rows); },
                             "Trajectory rows the run recorded, kept or streamed (without building a numpy view).")
      .def_property_readonly("shove", [](const RunResult& r) { return r.shove; })
      .def_property_readonly("warnings", [](const RunResult& r) { return r.warnings; })
      .def_property_readonly("config", [](const RunResult& r) { return r.config; })
      .def_property_readonly("timestep", [](const RunResult& r) { return r.timestep; })
      .def_property_readonly("sim_time", [](const RunResult& r) { return r.sim_time; })
      .def("metrics_json", [](const RunResult& r) { return simloop::metrics_json(r.metrics); })
      .def("trajectory_csv", [](const RunResult& r) {
        std::string text;
        {
          py::gil_scoped_release release;
          text = naming_failures("RunResult.trajectory_csv", [&] { return simloop::trajectory_csv(r.trajectory); });
        }
        return text;
      })
      .def("summary", [](const RunResult& r) { return simloop::summary_text(r); })
      .def(
          "write",
          [](const RunResult& r, const std::filesystem::path& out) {
            py::gil_scoped_release release;
            const simloop::OutputFiles files =
                naming_failures("RunResult.write(" + out.string() + ")", [&] { return simloop::write_outputs(r, out); });
            return std::make_pair(files.metrics, files.trajectory);
          },
          "out"_a);

  // The long calls: Ctrl-C stops them within a chunk of steps (see
  // Interruptible); progress(steps_done, steps_total), if given, is called
  // from this thread at most every 20 ms, and once at the end.
  m.def(
      "run",
      [](const simloop::Model& model, const simloop::RunConfig& config, py::object progress) {
        Interruptible work(std::move(progress));
        RunResult result = work.run([&](simloop::RunControl* control) {
          return naming_failures(run_call("run", config), [&] {
            simloop::Data workspace(model);
            return simloop::run(model, config, workspace, nullptr, control);
          });
        });
        work.finish();
        return result;
      },
      "model"_a, "config"_a, "progress"_a = py::none());
  m.def(
      "run_batch",
      [](const simloop::Model& model, const std::vector<simloop::RunConfig>& configs, int threads,
         py::object progress) {
        Interruptible work(std::move(progress));
        std::vector<RunResult> results = work.run([&](simloop::RunControl* control) {
          const std::string what = configs.empty() ? std::string("run_batch")
                                                   : run_call("run_batch", configs.front()) + " x " +
                                                         std::to_string(configs.size()) + " runs";
          return naming_failures(what, [&] { return simloop::run_batch(model, configs, threads, control); });
        });
        work.finish();
        return results;
      },
      "model"_a, "configs"_a, "threads"_a, "progress"_a = py::none());
  m.def("batch_workers", &simloop::batch_workers, "threads"_a, "jobs"_a);

  // Scenarios: the chapter's loop on any scene, as data (one parser: the
  // C++ one reads the TOML for both faces).
  py::class_<simloop::Scenario>(m, "Scenario", "A scenario: scene, timestep, length, controls, disturbances, recording.")
      .def_static("chapter", &simloop::Scenario::chapter, "The chapter's run as a scenario.")
      .def_static(
          "from_file", [](const std::string& path) { return simloop::Scenario::from_toml_file(path); }, "path"_a)
      .def_static(
          "from_toml",
          [](const std::string& text, const std::string& source, const std::string& base) {
            return simloop::Scenario::from_toml_string(text, source, base);
          },
          "text"_a, "source"_a = "<string>", "base"_a = "")
      .def_readonly("name", &simloop::Scenario::name)
      .def_property_readonly("scene", [](const simloop::Scenario& s) { return fs_str(s.scene.native()); })
      .def_readonly("timestep", &simloop::Scenario::timestep)
      .def_property_readonly("body_names", [](const simloop::Scenario& s) { return s.record.bodies; });
  m.def("load_scene", &simloop::load_scene, "scenario"_a);
  m.def(
      "check_scenario_names",
      [](const simloop::Scenario& s, const simloop::Model& model) { (void)simloop::resolve(s, model.get()); },
      "scenario"_a, "model"_a);
  m.def("scenario_from_flags", &simloop::cli::scenario_from_flags, "options"_a, "scene"_a);
  m.def(
      "check_run_inputs",
      [](simloop::cli::Options& opts, const simloop::Model& scene, const simloop::Scenario* scenario) {
        try {
          simloop::cli::check_run_inputs(opts, scene, scenario);
        } catch (const simloop::cli::UsageError& e) {
          throw py::value_error(e.what());
        }
      },
      "options"_a, "scene"_a, "scenario"_a = nullptr);
  m.def("scenario_config_from_flags", &simloop::cli::scenario_config, "options"_a);

  py::class_<simloop::ScenarioConfig>(m, "ScenarioConfig")
      .def(py::init([](std::uint64_t seed, const std::string& rng, std::optional<double> timestep,
                       std::optional<std::int64_t> steps, bool perturb, std::int64_t record_every) {
             const std::optional<simloop::ShoveRng> generator = simloop::parse_rng(rng);
             if (!generator) throw py::value_error("rng must be 'mt19937_64' or 'numpy', got '" + rng + "'");
             return simloop::ScenarioConfig{seed, *generator, timestep, steps, perturb, record_every};
           }),
           "seed"_a, "rng"_a, "timestep"_a, "steps"_a, "perturb"_a, "record_every"_a);

  py::class_<simloop::ScenarioRunResult>(m, "ScenarioResult", "What one run of a scenario did.")
      .def_readonly("name", &simloop::ScenarioRunResult::name)
      .def_readonly("seed", &simloop::ScenarioRunResult::seed)
      .def_readonly("rows", &simloop::ScenarioRunResult::rows)
      .def_readonly("timestep", &simloop::ScenarioRunResult::timestep)
      .def_readonly("sim_time", &simloop::ScenarioRunResult::sim_time)
      .def_readonly("warnings", &simloop::ScenarioRunResult::warnings)
      .def_property_readonly("steps", [](const simloop::ScenarioRunResult& r) { return r.schedule.steps; })
      .def_property_readonly("column_names",
                             [](const simloop::ScenarioRunResult& r) {
                               py::tuple names(r.columns.size());
                               for (size_t i = 0; i < r.columns.size(); ++i) names[i] = py::str(r.columns[i].name);
                               return names;
                             })
      .def_property_readonly("column_units",
                             [](const simloop::ScenarioRunResult& r) {
                               py::dict units;
                               for (const simloop::Column& c : r.columns) units[py::str(c.name)] = c.unit;
                               return units;
                             })
      .def_property_readonly(
          "trajectory",
          [](const py::object& self) {
            return trajectory_view(self, self.cast<const simloop::ScenarioRunResult&>().trajectory);
          },
          "(rows, columns) read-only float64 view; columns as in column_names.")
      .def(
          "column",
          [](const py::object& self, const std::string& name) {
            const auto& r = self.cast<const simloop::ScenarioRunResult&>();
            for (size_t c = 0; c < r.columns.size(); ++c) {
              if (r.columns[c].name == name) return column_view(self, r.trajectory, static_cast<int>(c));
            }
            throw py::key_error("no trajectory column named '" + name + "'; see result.column_names");
          },
          "name"_a)
      .def_property_readonly("disturbances",
                             [](const simloop::ScenarioRunResult& r) {
                               py::list out;
                               for (size_t i = 0; i < r.schedule.forces.size(); ++i) {
                                 const simloop::Schedule::Force& f = r.schedule.forces[i];
                                 out.append(py::dict("body"_a = r.disturbed_bodies[i],
                                                     "force"_a = vec(f.wrench.data(), 3),
                                                     "torque"_a = vec(f.wrench.data() + 3, 3),
                                                     "start_step"_a = f.start, "end_step"_a = f.end,
                                                     "asked_end_step"_a = f.asked_end));
                               }
                               return out;
                             })
      .def_property_readonly("bodies", [](const simloop::ScenarioRunResult& r) { return simloop::recorded_bodies(r); },
                             "The recorded bodies: {name: the column of its _x}.")
      .def("metrics_json", &simloop::scenario_metrics_json)
      .def("summary", &simloop::scenario_summary)
      .def(
          "write",
          [](const simloop::ScenarioRunResult& r, const std::filesystem::path& out) {
            py::gil_scoped_release release;
            const simloop::OutputFiles files = simloop::write_scenario_outputs(r, out);
            return std::make_pair(files.metrics, files.trajectory);
          },
          "out"_a);
  m.def(
      "run_scenario",
      [](const simloop::Model& scene, const simloop::Scenario& scenario, const simloop::ScenarioConfig& config,
         py::object progress) {
        Interruptible work(std::move(progress));
        simloop::ScenarioRunResult result = work.run([&](simloop::RunControl* control) {
          return naming_failures("run_scenario(" + scenario.name + ")", [&] {
            return simloop::run_scenario(scene, scenario, config, nullptr, nullptr, control);
          });
        });
        work.finish();
        return result;
      },
      "scene"_a, "scenario"_a, "config"_a, "progress"_a = py::none());
  m.def(
      "run_scenario_batch",
      [](const simloop::Model& scene, const simloop::Scenario& scenario,
         const std::vector<simloop::ScenarioConfig>& configs, int threads, py::object progress) {
        Interruptible work(std::move(progress));
        std::vector<simloop::ScenarioRunResult> results = work.run([&](simloop::RunControl* control) {
          return naming_failures("run_scenario_batch(" + scenario.name + ") x " + std::to_string(configs.size()) +
                                     " runs",
                                 [&] { return simloop::run_scenario_batch(scene, scenario, configs, threads, control); });
        });
        work.finish();
        return results;
      },
      "scene"_a, "scenario"_a, "configs"_a, "threads"_a, "progress"_a = py::none());
  m.def(
      "scene_geometry",
      [](const simloop::Model& model) {
        static constexpr const char* kKinds[] = {"plane", "sphere", "capsule", "ellipsoid", "cylinder", "box", "mesh", "other"};
        py::list out;
        for (const simloop::GeomShape& g : simloop::scene_geometry(model.get())) {
          out.append(py::dict("name"_a = g.name, "body"_a = g.body, "body_id"_a = g.body_id,
                              "kind"_a = kKinds[static_cast<int>(g.kind)], "half_size"_a = vec(g.half_size.data(), 3),
                              "mesh_center"_a = vec(g.mesh_center.data(), 3), "pos"_a = vec(g.pos.data(), 3),
                              "quat"_a = vec(g.quat.data(), 4),
                              "rgba"_a = py::make_tuple(g.rgba[0], g.rgba[1], g.rgba[2], g.rgba[3])));
        }
        return out;
      },
      "model"_a, "Every visible geom: its shape, its pose on its body, its colour.");

  py::class_<simloop::Contact>(m, "Contact")
      .def_readonly("geom1", &simloop::Contact::geom1)
      .def_readonly("geom2", &simloop::Contact::geom2)
      .def_readonly("dist", &simloop::Contact::dist)
      .def_property_readonly("pos", [](const simloop::Contact& c) { return vec(c.pos.data(), 3); })
      .def("__repr__", [](const simloop::Contact& c) {
        return "Contact(" + c.geom1 + ", " + c.geom2 + ", dist=" + simloop::python_float_repr(c.dist) + ")";
      });

  // Every call holds the Sim's lock (PySim, SimLock): safe from any thread.
  // The arrays (array()) are views into the Sim's mjData and take no lock:
  // see simloop.Sim's docstring for what that means across threads.
  py::class_<PySim>(m, "Sim")
      .def(py::init([](const simloop::Model& model) {
             return naming_failures("Sim", [&] { return std::make_unique<PySim>(model); });
           }),
           "model"_a)
      .def("copy", [](PySim& s) {
        SimLock lock(s);
        return naming_failures("Sim.copy", [&] { return std::make_unique<PySim>(s.sim); });
      }, "An independent copy: its own data, the same (shared, read-only) model.")
      .def("reset", locked(&simloop::Sim::reset))
      .def("reset_to_keyframe", locked(&simloop::Sim::reset_to_keyframe), "key"_a)
      .def("set_timestep", locked(&simloop::Sim::set_timestep), "timestep"_a)
      .def_property_readonly("timestep", locked(&simloop::Sim::timestep))
      .def("set_ctrl", [](PySim& s, double value) {
        SimLock lock(s);
        s.sim.set_ctrl(value);
      }, "value"_a)
      .def("set_ctrl_vector", [](PySim& s, const py::array_t<double, py::array::c_style | py::array::forcecast>& values) {
        SimLock lock(s);
        s.sim.set_ctrl(values.data(), static_cast<size_t>(values.size()));
      }, "values"_a)
      .def_property_readonly("ctrl", locked(&simloop::Sim::ctrl))
      .def("apply_force", locked(&simloop::Sim::apply_force), "force"_a)
      .def("clear_force", locked(&simloop::Sim::clear_force))
      .def("apply_wrench", [](PySim& s, int body, std::optional<std::array<double, 3>> force,
                              std::optional<std::array<double, 3>> torque) {
        SimLock lock(s);
        s.sim.apply_wrench(body, force ? &*force : nullptr, torque ? &*torque : nullptr);
      }, "body"_a, "force"_a, "torque"_a)
      .def("clear_forces", locked(&simloop::Sim::clear_forces))
      .def_property_readonly("applied_force", [](PySim& s) {
        SimLock lock(s);
        return vec(s.sim.applied_force().data(), 3);
      })
      .def("forward", locked(&simloop::Sim::forward))
      .def("get_state", [](PySim& s) {
        SimLock lock(s);
        const std::vector<double> state = s.sim.state();
        return vec(state.data(), state.size());
      })
      .def("set_state", [](PySim& s, const py::array_t<double, py::array::c_style>& state) {
        SimLock lock(s);
        s.sim.set_state(state.data(), static_cast<size_t>(state.size()));
      }, "state"_a)
      .def_property_readonly("state_layout", [](PySim& s) {
        SimLock lock(s);
        return s.sim.state_layout();
      })
      .def("id", [](PySim& s, const std::string& kind, const std::string& name) {
        SimLock lock(s);  // set_timestep may be swapping the model on another thread
        return s.sim.id(object_type(kind), name);
      }, "kind"_a, "name"_a)
      .def("checked_index", [](PySim& s, const std::string& kind, long long index) {
        SimLock lock(s);
        return s.sim.checked_index(object_type(kind), index);
      }, "kind"_a, "index"_a)
      .def("body_velocity", [](PySim& s, int body) {
        SimLock lock(s);
        return vec(s.sim.body_velocity(body).data(), 6);
      }, "body"_a)
      .def_property_readonly("model", [](PySim& s) {
        SimLock lock(s);
        return s.sim.model();
      }, "This Sim's own model (with its timestep).")
      .def(
          "array",
          [](const py::object& self, const std::string& name) {
            PySim& s = self.cast<PySim&>();
            SimLock lock(s);  // for the model's sizes; the view itself outlives the lock, as documented
            const mjModel* mm = s.sim.model().get();
            mjData* d = s.sim.data();
            // Inputs and state: writable. What MuJoCo derives: read-only.
            if (name == "qpos") return owned_view(self, d->qpos, mm->nq, 0, true);
            if (name == "qvel") return owned_view(self, d->qvel, mm->nv, 0, true);
            if (name == "ctrl") return owned_view(self, d->ctrl, mm->nu, 0, true);
            if (name == "act") return owned_view(self, d->act, mm->na, 0, true);
            if (name == "qfrc_applied") return owned_view(self, d->qfrc_applied, mm->nv, 0, true);
            if (name == "xfrc_applied") return owned_view(self, d->xfrc_applied, mm->nbody, 6, true);
            if (name == "sensordata") return owned_view(self, d->sensordata, mm->nsensordata, 0, false);
            if (name == "actuator_force") return owned_view(self, d->actuator_force, mm->nu, 0, false);
            if (name == "xpos") return owned_view(self, d->xpos, mm->nbody, 3, false);
            if (name == "xquat") return owned_view(self, d->xquat, mm->nbody, 4, false);
            throw py::value_error("no Sim array named '" + name + "'");
          },
          "name"_a, "A numpy view into this Sim's mjData (keeps the Sim alive).")
      .def(
          "step",
          [](PySim& s, std::int64_t n) {
            SimLock lock(s);
            if (n <= simloop::RunControl::kChunkSteps) {
              // One chunk: nothing to interrupt, so no RunControl to pay for
              // (Python checks for Ctrl-C between the calls of a tight loop).
              py::gil_scoped_release release;
              s.sim.step(n);
              return;
            }
            Interruptible work{py::none()};
            work.run([&](simloop::RunControl* control) { s.sim.step(n, control); });
          },
          "n"_a)
      .def(
          "step_with_progress",
          [](PySim& s, std::int64_t n, py::object progress) {
            SimLock lock(s);
            Interruptible work(std::move(progress));
            work.run([&](simloop::RunControl* control) { s.sim.step(n, control); });
            work.finish();
          },
          "n"_a, "progress"_a)
      .def_property_readonly("time", locked(&simloop::Sim::time))
      .def_property_readonly("steps_taken", locked(&simloop::Sim::steps_taken))
      .def_property_readonly("box_position", [](PySim& s) {
        SimLock lock(s);
        return vec(s.sim.box_position().data(), 3);
      })
      .def_property_readonly("box_quaternion", [](PySim& s) {
        SimLock lock(s);
        return vec(s.sim.box_quaternion().data(), 4);
      })
      .def_property_readonly("box_velocity", [](PySim& s) {
        SimLock lock(s);
        return vec(s.sim.box_velocity().data(), 3);
      })
      .def_property_readonly("pusher_x", locked(&simloop::Sim::pusher_x))
      .def_property_readonly("pusher_velocity", locked(&simloop::Sim::pusher_velocity))
      .def_property_readonly("contacts", locked(&simloop::Sim::contacts))
      .def_property_readonly("warnings", locked(&simloop::Sim::warnings))
      // Pickled as its model (MuJoCo's binary, with this Sim's timestep), its
      // full state and its step count; MuJoCo's warnings are not carried.
      .def(py::pickle(
          [](PySim& s) {
            SimLock lock(s);
            const std::vector<double> state = s.sim.state();
            return py::make_tuple(s.sim.model(), vec(state.data(), state.size()), s.sim.steps_taken());
          },
          [](const py::tuple& t) {
            if (t.size() != 3) throw py::value_error("cannot unpickle a Sim: expected (model, state, steps_taken)");
            auto s = std::make_unique<PySim>(t[0].cast<simloop::Model>());
            const auto state = t[1].cast<py::array_t<double, py::array::c_style | py::array::forcecast>>();
            s->sim.set_state(state.data(), static_cast<size_t>(state.size()));
            s->sim.set_steps_taken(t[2].cast<std::int64_t>());
            return s;
          }));

  m.def("pusher_track", [](const simloop::Model& model) {
    const simloop::PusherTrack t = simloop::pusher_track(model);
    return py::make_tuple(vec(t.rest_position.data(), 3), vec(t.axis.data(), 3), t.q0);
  });

  py::class_<simloop::SweepPoint>(m, "SweepPoint", "One timestep of a sweep.")
      .def_readonly("timestep", &simloop::SweepPoint::timestep)
      .def_readonly("steps", &simloop::SweepPoint::steps)
      .def_readonly("peak_box_z", &simloop::SweepPoint::peak_box_z)
      .def_readonly("max_abs_box_y", &simloop::SweepPoint::max_abs_box_y)
      .def_readonly("final_box_x", &simloop::SweepPoint::final_box_x)
      .def_readonly("final_box_y", &simloop::SweepPoint::final_box_y)
      .def_readonly("final_box_z", &simloop::SweepPoint::final_box_z)
      .def_readonly("final_pusher_x", &simloop::SweepPoint::final_pusher_x)
      .def_readonly("warnings", &simloop::SweepPoint::warnings)
      .def_property_readonly("work_constraint_positive",
                             [](const simloop::SweepPoint& p) { return p.energy.work_constraint_positive; })
      .def_property_readonly("energy_unexplained", [](const simloop::SweepPoint& p) { return p.energy.unexplained; })
      .def_property_readonly("energy_change",
                             [](const simloop::SweepPoint& p) { return p.energy.energy_end - p.energy.energy_start; })
      .def_readonly("stable", &simloop::SweepPoint::stable);
  py::class_<simloop::SweepResult>(m, "SweepResult", "A timestep sweep of the baseline run.")
      .def_readonly("duration", &simloop::SweepResult::duration)
      .def_readonly("points", &simloop::SweepResult::points)
      .def_property_readonly("edge", [](const simloop::SweepResult& r) -> py::object {
        if (r.edge_index < 0) return py::none();
        return py::float_(r.points[static_cast<size_t>(r.edge_index)].timestep);
      }, "The largest stable timestep (None if even the finest is unstable).")
      .def("csv", &simloop::sweep_csv)
      .def("summary", &simloop::sweep_summary)
      .def(
          "write",
          [](const simloop::SweepResult& r, const std::filesystem::path& out) {
            simloop::prepare_output_dir(out);
            simloop::write_file_atomically(out / "sweep.csv", simloop::sweep_csv(r));
            return out / "sweep.csv";
          },
          "out"_a, "Writes sweep.csv into out (atomically); returns its path.");
  m.def(
      "sweep",
      [](const simloop::Model& model, const std::vector<double>& timesteps, double duration, int threads,
         py::object progress) {
        Interruptible work(std::move(progress));
        simloop::SweepResult result = work.run([&](simloop::RunControl* control) {
          return naming_failures("sweep(" + std::to_string(timesteps.size()) + " timesteps, duration=" +
                                     simloop::python_float_repr(duration) + ")",
                                 [&] { return simloop::sweep(model, timesteps, duration, threads, control); });
        });
        work.finish();
        return result;
      },
      "model"_a, "timesteps"_a, "duration"_a, "threads"_a, "progress"_a = py::none());
  m.def("log_spaced", &simloop::log_spaced, "start"_a, "stop"_a, "count"_a);
  m.def("default_sweep_timesteps", &simloop::default_sweep_timesteps,
        "The default sweep's 25 round timesteps (1, 2, 3, 4, 5, 6, 8 per decade, 0.0005 s to 1 s).");
  m.attr("STABLE_HOP") = simloop::kStableHop;
  m.attr("STABLE_SINK") = simloop::kStableSink;
  m.attr("BOX_REST_Z") = simloop::kBoxRestZ;

  // The command line, parsed by the same code as sim_loop's.
  py::class_<simloop::cli::Options>(m, "CommandLine")
      .def_property_readonly("command", [](const simloop::cli::Options& o) {
        return o.command == simloop::cli::Command::kSweep ? "sweep" : "run";
      })
      .def_readonly("sweep_timesteps", &simloop::cli::Options::sweep_timesteps)
      .def_readonly("sweep_duration", &simloop::cli::Options::sweep_duration)
      .def_readonly("threads", &simloop::cli::Options::threads)
      .def_readonly("plot", &simloop::cli::Options::plot)
      .def_readonly("run", &simloop::cli::Options::run)
      // Paths as Python spells file names: undecodable bytes as surrogates.
      .def_property_readonly("out", [](const simloop::cli::Options& o) { return fs_str(o.out.native()); })
      .def_property_readonly("model_path", [](const simloop::cli::Options& o) { return fs_str(o.model_path); })
      .def_readonly("rerun", &simloop::cli::Options::rerun)
      .def_property_readonly("is_scenario", &simloop::cli::Options::is_scenario)
      .def_property_readonly("scenario_path", [](const simloop::cli::Options& o) { return fs_str(o.scenario_path); })
      .def_readonly("help", &simloop::cli::Options::help)
      .def_readonly("version", &simloop::cli::Options::version);
  // args: str (sys.argv's, encoded back to the bytes the shell passed, as
  // os.fsencode does) or bytes.
  m.def("parse_command_line", [](const std::vector<py::object>& args) {
    std::vector<std::string> bytes;
    for (const py::object& a : args) {
      PyObject* encoded = PyUnicode_Check(a.ptr()) ? PyUnicode_EncodeFSDefault(a.ptr()) : nullptr;
      if (PyUnicode_Check(a.ptr()) && !encoded) throw py::error_already_set();
      const py::object raw = encoded ? py::reinterpret_steal<py::object>(encoded) : a;
      if (!PyBytes_Check(raw.ptr())) throw py::type_error("command line arguments must be str or bytes");
      bytes.emplace_back(PyBytes_AS_STRING(raw.ptr()), static_cast<size_t>(PyBytes_GET_SIZE(raw.ptr())));
    }
    std::vector<const char*> argv = {"simloop"};
    for (const std::string& a : bytes) argv.push_back(a.c_str());
    try {
      return simloop::cli::parse(static_cast<int>(argv.size()), argv.data());
    } catch (const simloop::cli::UsageError& e) {
      set_error_fs(PyExc_ValueError, e.what());
      throw py::error_already_set();
    }
  });
  m.def("help_text", &simloop::cli::help_text, "program"_a, "recording"_a);
  m.def("sweep_help_text", &simloop::cli::sweep_help_text, "program"_a);
  m.def("prepare_output_dir", &simloop::prepare_output_dir, "dir"_a);
  m.def("write_file_atomically", [](const std::filesystem::path& path, const std::string& contents) {
    simloop::write_file_atomically(path, contents);
  }, "path"_a, "contents"_a);

  // --- Batches of the caller's own inputs, metrics-only batches, reprs ---
  // (simloop/scenario.py and simloop/tables.py hold the Python side.)
  m.def(
      "run_scenario_with_inputs",
      [](const simloop::Model& scene, const simloop::Scenario& scenario, const simloop::ScenarioConfig& config,
         std::optional<DoubleArray> controls, std::optional<DoubleArray> initial_state, py::object progress) {
        const simloop::RunInputs inputs = run_inputs(1, controls, initial_state).front();
        Interruptible work(std::move(progress));
        simloop::ScenarioRunResult result = work.run([&](simloop::RunControl* control) {
          return naming_failures("run_scenario(" + scenario.name + ")", [&] {
            return simloop::run_scenario(scene, scenario, config, nullptr, nullptr, control, inputs);
          });
        });
        work.finish();
        return result;
      },
      "scene"_a, "scenario"_a, "config"_a, "controls"_a, "initial_state"_a, "progress"_a = py::none());
  m.def(
      "run_scenario_batch_with_inputs",
      [](const simloop::Model& scene, const simloop::Scenario& scenario,
         const std::vector<simloop::ScenarioConfig>& configs, int threads, std::optional<DoubleArray> controls,
         std::optional<DoubleArray> initial_state, bool keep_rows, py::object progress) {
        std::vector<simloop::RunInputs> inputs;
        if (controls || initial_state) inputs = run_inputs(configs.size(), controls, initial_state);
        Interruptible work(std::move(progress));
        std::vector<simloop::ScenarioRunResult> results = work.run([&](simloop::RunControl* control) {
          return naming_failures("run_scenario_batch(" + scenario.name + ") x " + std::to_string(configs.size()) +
                                     " runs",
                                 [&] {
                                   return simloop::run_scenario_batch(scene, scenario, configs, threads, control,
                                                                      inputs, keep_rows);
                                 });
        });
        work.finish();
        return results;
      },
      "scene"_a, "scenario"_a, "configs"_a, "threads"_a, "controls"_a, "initial_state"_a, "keep_rows"_a,
      "progress"_a = py::none());
  m.def(
      "run_batch_metrics_only",
      [](const simloop::Model& model, const std::vector<simloop::RunConfig>& configs, int threads,
         py::object progress) {
        simloop::DiscardRows discard;  // stateless: shared by every run
        const std::vector<simloop::RowSink*> sinks(configs.size(), &discard);
        Interruptible work(std::move(progress));
        std::vector<RunResult> results = work.run([&](simloop::RunControl* control) {
          return naming_failures("run_batch(metrics_only=True) x " + std::to_string(configs.size()) + " runs",
                                 [&] { return simloop::run_batch(model, configs, sinks, threads, control); });
        });
        work.finish();
        return results;
      },
      "model"_a, "configs"_a, "threads"_a, "progress"_a = py::none());

  auto run_result = py::reinterpret_borrow<py::class_<RunResult>>(m.attr("RunResult"));
  run_result
      .def_property_readonly("unrounded_metrics", [](const RunResult& r) { return metrics_dict(r.unrounded_metrics); },
                             "metrics as computed, not rounded (metrics.json rounds to 6 decimals).")
      .def("__repr__", [](const RunResult& r) {
        return "RunResult(seed=" + std::to_string(r.config.seed) + ", steps=" + std::to_string(r.metrics.steps) +
               ", timestep=" + simloop::python_float_repr(r.timestep) + ", rows=" +
               std::to_string(r.trajectory.rows()) + ", lateral_drift=" +
               simloop::python_float_repr(r.metrics.lateral_drift) + ", warnings=" + std::to_string(r.warnings.size()) +
               ")";
      });
  py::reinterpret_borrow<py::class_<simloop::RunConfig>>(m.attr("RunConfig"))
      .def("__repr__", [](const simloop::RunConfig& c) {
        return "RunConfig(seed=" + std::to_string(c.seed) + ", steps=" + std::to_string(c.steps) +
               ", timestep=" + simloop::python_float_repr(c.timestep) + ", perturb=" + py_bool(c.perturb) +
               ", smoke=" + py_bool(c.smoke) + ", record_every=" + std::to_string(c.record_every) +
               ", audit_energy=" + py_bool(c.audit_energy) + ", rng='" + std::string(simloop::rng_name(c.rng)) + "')";
      });
  py::reinterpret_borrow<py::class_<simloop::SweepPoint>>(m.attr("SweepPoint"))
      .def("__repr__", [](const simloop::SweepPoint& p) {
        return "SweepPoint(timestep=" + simloop::python_float_repr(p.timestep) + ", steps=" + std::to_string(p.steps) +
               ", stable=" + py_bool(p.stable) + ", peak_box_z=" + simloop::python_float_repr(simloop::round6(p.peak_box_z)) +
               ", warnings=" + std::to_string(p.warnings) + ")";
      });
  py::reinterpret_borrow<py::class_<simloop::SweepResult>>(m.attr("SweepResult"))
      .def("__repr__", [](const simloop::SweepResult& r) {
        const std::string edge =
            r.edge_index < 0 ? "None"
                             : simloop::python_float_repr(r.points[static_cast<std::size_t>(r.edge_index)].timestep);
        std::string range;
        if (!r.points.empty()) {
          range = ", timesteps=" + simloop::python_float_repr(r.points.front().timestep) + ".." +
                  simloop::python_float_repr(r.points.back().timestep);
        }
        return "SweepResult(points=" + std::to_string(r.points.size()) + range + ", duration=" +
               simloop::python_float_repr(r.duration) + ", edge=" + edge + ")";
      });
  py::reinterpret_borrow<py::class_<simloop::ScenarioConfig>>(m.attr("ScenarioConfig"))
      .def("__repr__", [](const simloop::ScenarioConfig& c) {
        return "ScenarioConfig(seed=" + std::to_string(c.seed) + ", rng='" + std::string(simloop::rng_name(c.rng)) +
               "', timestep=" + (c.timestep ? simloop::python_float_repr(*c.timestep) : std::string("None")) +
               ", steps=" + (c.steps ? std::to_string(*c.steps) : std::string("None")) + ", perturb=" +
               py_bool(c.perturb) + ", record_every=" + std::to_string(c.record_every) + ")";
      });
  py::reinterpret_borrow<py::class_<simloop::ScenarioRunResult>>(m.attr("ScenarioResult"))
      .def_readonly("rng", &simloop::ScenarioRunResult::rng)
      .def_readonly("perturb", &simloop::ScenarioRunResult::perturb)
      .def_property_readonly("final_row", [](const simloop::ScenarioRunResult& r) { return vector_array(r.final_row); },
                             "The last row (columns as column_names), kept or not: a copy.")
      .def_property_readonly(
          "final_state", [](const simloop::ScenarioRunResult& r) { return vector_array(r.final_state); },
          "The full state at the end (the flat layout of state.hpp): an initial_state that continues this run.")
      .def("__repr__", [](const simloop::ScenarioRunResult& r) {
        return "ScenarioResult(name=" + py_str_repr(r.name) + ", seed=" + std::to_string(r.seed) + ", steps=" +
               std::to_string(r.schedule.steps) + ", timestep=" + simloop::python_float_repr(r.timestep) +
               ", rows=" + std::to_string(r.trajectory.rows()) + ", columns=" + std::to_string(r.columns.size()) +
               ", disturbances=" + std::to_string(r.schedule.forces.size()) +
               ", warnings=" + std::to_string(r.warnings.size()) + ")";
      });
  py::reinterpret_borrow<py::class_<simloop::Scenario>>(m.attr("Scenario"))
      .def("__repr__", [](const simloop::Scenario& s) {
        std::string length;
        switch (s.length.unit) {
          case simloop::When::Unit::kSteps: length = "steps=" + std::to_string(s.length.count); break;
          case simloop::When::Unit::kSeconds: length = "duration=" + simloop::python_float_repr(s.length.value); break;
          default: length = "length=" + simloop::python_float_repr(s.length.value); break;
        }
        std::string controls;
        for (const simloop::ControlSpec& c : s.controls) controls += (controls.empty() ? "" : ", ") + py_str_repr(c.actuator);
        std::string recorded;
        for (const std::string& b : s.record.bodies) recorded += (recorded.empty() ? "" : ", ") + py_str_repr(b);
        return "Scenario(name=" + py_str_repr(s.name) + ", scene=" +
               (s.scene.empty() ? std::string("None") : py::repr(fs_str(s.scene.native())).cast<std::string>()) +
               ", timestep=" + (s.timestep ? simloop::python_float_repr(*s.timestep) : std::string("None")) + ", " +
               length + ", controls=[" + controls + "], disturbances=" + std::to_string(s.disturbances.size()) +
               ", bodies=[" + recorded + "])";
      });

  // Scenario sweeps; a scenario's run streamed to its files, with the rows of
  // every moving body's pose handed to Python for the recording.
  py::class_<simloop::ScenarioSweepPoint>(m, "ScenarioSweepPoint", "One timestep of a scenario sweep.")
      .def_readonly("timestep", &simloop::ScenarioSweepPoint::timestep)
      .def_readonly("steps", &simloop::ScenarioSweepPoint::steps)
      .def_readonly("mujoco_warnings", &simloop::ScenarioSweepPoint::mujoco_warnings)
      .def_readonly("diverged", &simloop::ScenarioSweepPoint::diverged)
      .def_readonly("peak_speed", &simloop::ScenarioSweepPoint::peak_speed)
      .def_readonly("final_positions", &simloop::ScenarioSweepPoint::final_positions)
      .def_readonly("offsets", &simloop::ScenarioSweepPoint::offsets)
      .def_readonly("max_offset", &simloop::ScenarioSweepPoint::max_offset)
      .def_readonly("blew_up", &simloop::ScenarioSweepPoint::blew_up)
      .def("__repr__", [](const simloop::ScenarioSweepPoint& p) {
        return "ScenarioSweepPoint(timestep=" + simloop::python_float_repr(p.timestep) +
               ", blew_up=" + (p.blew_up ? "True" : "False") + ")";
      });
  py::class_<simloop::ScenarioSweepResult>(m, "ScenarioSweepResult", "A timestep sweep of a scenario.")
      .def_readonly("name", &simloop::ScenarioSweepResult::name)
      .def_readonly("duration", &simloop::ScenarioSweepResult::duration)
      .def_readonly("bodies", &simloop::ScenarioSweepResult::bodies)
      .def_readonly("scene_size", &simloop::ScenarioSweepResult::scene_size)
      .def_readonly("tolerance", &simloop::ScenarioSweepResult::tolerance)
      .def_readonly("points", &simloop::ScenarioSweepResult::points)
      .def_property_readonly("edge", [](const simloop::ScenarioSweepResult& r) -> py::object {
        if (r.edge_index < 0) return py::none();
        return py::float_(r.points[static_cast<size_t>(r.edge_index)].timestep);
      }, "The largest timestep before any blew up (None if even the finest did).")
      .def("csv", &simloop::scenario_sweep_csv)
      .def("summary", &simloop::scenario_sweep_summary)
      .def(
          "write",
          [](const simloop::ScenarioSweepResult& r, const std::filesystem::path& out) {
            simloop::prepare_output_dir(out);
            simloop::write_file_atomically(out / "sweep.csv", simloop::scenario_sweep_csv(r));
            return out / "sweep.csv";
          },
          "out"_a, "Writes sweep.csv into out (atomically); returns its path.");
  m.def(
      "sweep_scenario",
      [](const simloop::Model& scene, const simloop::Scenario& scenario, const std::vector<double>& timesteps,
         double duration, const simloop::ScenarioConfig& config, int threads, py::object progress) {
        Interruptible work(std::move(progress));
        simloop::ScenarioSweepResult result = work.run([&](simloop::RunControl* control) {
          return naming_failures("sweep(scenario=" + scenario.name + ", " + std::to_string(timesteps.size()) +
                                     " timesteps, duration=" + simloop::python_float_repr(duration) + ")",
                                 [&] {
                                   return simloop::sweep_scenario(scene, scenario, timesteps, duration, config,
                                                                  threads, control);
                                 });
        });
        work.finish();
        return result;
      },
      "scene"_a, "scenario"_a, "timesteps"_a, "duration"_a, "config"_a, "threads"_a, "progress"_a = py::none());
  m.def("scenario_duration", &simloop::scenario_duration, "scene"_a, "scenario"_a);
  m.def("default_scenario_sweep_timesteps", &simloop::default_scenario_sweep_timesteps, "duration"_a);
  m.attr("SCENARIO_SWEEP_TOLERANCE") = simloop::kScenarioSweepTolerance;
  m.def("moving_bodies", &simloop::moving_bodies, "scene"_a);
  // run_to_files, run_scenario_to_files, OutputLock, PipedFile: bindings_outputs.cc
  bind_outputs(m);
  // --- Model views and names, and pickling Model, RunResult, ScenarioResult
  // (Sim pickles above). Results pickle field by field, bits unchanged, so
  // they come back from multiprocessing workers as they were.
  auto model_class = py::reinterpret_borrow<py::class_<simloop::Model>>(m.attr("Model"));
  model_class
      .def_property_readonly("name", &simloop::Model::name, "<mujoco model=...>'s name ('' if none).")
      .def_property_readonly("has_chapter_layout", &simloop::Model::has_chapter_layout,
                             "True if the scene has the chapter's box and pusher (the chapter's loop runs on it).")
      .def_property_readonly("nbody", [](const simloop::Model& model) { return model.get()->nbody; })
      .def_property_readonly("njnt", [](const simloop::Model& model) { return model.get()->njnt; })
      .def_property_readonly("na", [](const simloop::Model& model) { return model.get()->na; })
      .def_property_readonly("nsensor", [](const simloop::Model& model) { return model.get()->nsensor; })
      .def_property_readonly("nsensordata", [](const simloop::Model& model) { return model.get()->nsensordata; })
      .def_property_readonly("nkey", [](const simloop::Model& model) { return model.get()->nkey; })
      .def(
          "names",
          &model_names,
          "kind"_a, "Every object's name of a kind, by index ('' for an unnamed one).")
      .def(
          "object_info",
          [](const simloop::Model& model, const std::string& kind, int id) {
            // The model's fixed facts the named views need, as plain values.
            const mjModel* raw = model.get();
            const mjtObj type = object_type(kind);
            if (id < 0 || static_cast<size_t>(id) >= py::len(model_names(model, kind))) throw py::value_error(kind + " id out of range");
            if (type == mjOBJ_BODY) return py::dict("mass"_a = raw->body_mass[id]);
            if (type == mjOBJ_JOINT) {
              static constexpr const char* kTypes[] = {"free", "ball", "slide", "hinge"};
              const int t = raw->jnt_type[id];
              const int nq = t == mjJNT_FREE ? 7 : t == mjJNT_BALL ? 4 : 1;
              const int nv = t == mjJNT_FREE ? 6 : t == mjJNT_BALL ? 3 : 1;
              return py::dict("type"_a = kTypes[t], "qposadr"_a = raw->jnt_qposadr[id], "nq"_a = nq,
                              "dofadr"_a = raw->jnt_dofadr[id], "nv"_a = nv, "body"_a = raw->jnt_bodyid[id]);
            }
            if (type == mjOBJ_ACTUATOR) {
              return py::dict("ctrlrange"_a = py::make_tuple(raw->actuator_ctrlrange[2 * id],
                                                             raw->actuator_ctrlrange[2 * id + 1]),
                              "ctrllimited"_a = raw->actuator_ctrllimited[id] != 0);
            }
            if (type == mjOBJ_SENSOR) {
              return py::dict("adr"_a = raw->sensor_adr[id], "dim"_a = raw->sensor_dim[id]);
            }
            return py::dict();
          },
          "kind"_a, "id"_a)
      .def(py::pickle([](const simloop::Model& model) { return py::bytes(model.to_bytes()); },
                      [](const py::bytes& bytes) { return simloop::Model::from_bytes(std::string(bytes)); }));
  py::reinterpret_borrow<py::class_<RunResult>>(m.attr("RunResult"))
      .def(py::pickle(&pickle_fields<RunResult, &run_result_fields<FieldWriter, const RunResult>>, [](const py::tuple& t) {
        return unpickle_fields<RunResult, &run_result_fields<FieldReader, RunResult>>(t, "RunResult");
      }));
  py::reinterpret_borrow<py::class_<simloop::ScenarioRunResult>>(m.attr("ScenarioResult"))
      .def(py::pickle(
          &pickle_fields<simloop::ScenarioRunResult, &scenario_result_fields<FieldWriter, const simloop::ScenarioRunResult>>,
          [](const py::tuple& t) {
            return unpickle_fields<simloop::ScenarioRunResult,
                                   &scenario_result_fields<FieldReader, simloop::ScenarioRunResult>>(t, "ScenarioResult");
          }));
  // ---- Batches past one machine (python/simloop/distributed.py) ----------
  // Scene parameters on a copy of a model, the warning names a table's
  // columns are made of, and sweep points as plain data (so a sweep run in
  // chunks on workers is put back together as one SweepResult).
  m.def(
      "with_scene_params",
      [](const simloop::Model& model, const std::vector<std::tuple<std::string, std::string, double>>& params) {
        std::vector<simloop::SceneParam> converted;
        for (const auto& [kind, name, value] : params) {
          simloop::SceneParam p;
          if (kind == "friction") {
            p.kind = simloop::SceneParam::Kind::kFriction;
          } else if (kind == "mass") {
            p.kind = simloop::SceneParam::Kind::kMass;
          } else if (kind == "damping") {
            p.kind = simloop::SceneParam::Kind::kDamping;
          } else {
            throw py::value_error("scene parameter kind must be 'friction', 'mass' or 'damping', got '" + kind + "'");
          }
          p.name = name;
          p.value = value;
          converted.push_back(p);
        }
        return simloop::with_scene_params(model, converted);
      },
      "model"_a, "params"_a, "A copy of model with (kind, name, value) scene parameters applied.");
  m.attr("WARNING_NAMES") = py::tuple(py::cast(simloop::detail::all_warning_names()));
  m.def(
      "sweep_point_fields",
      [](const simloop::SweepPoint& p) {
        const simloop::EnergyTotals& e = p.energy;
        return py::make_tuple(p.timestep, p.steps, p.peak_box_z, p.max_abs_box_y, p.final_box_x, p.final_box_y,
                              p.final_box_z, p.final_pusher_x, p.warnings,
                              py::make_tuple(e.energy_start, e.energy_end, e.work_actuator, e.work_shove,
                                             e.work_passive, e.work_constraint, e.work_constraint_positive,
                                             e.unexplained));
      },
      "point"_a);
  m.def(
      "sweep_result_from_fields",
      [](double duration, const std::vector<py::tuple>& points) {
        simloop::SweepResult result;
        result.duration = duration;
        for (const py::tuple& f : points) {
          simloop::SweepPoint p;
          p.timestep = f[0].cast<double>();
          p.steps = f[1].cast<std::int64_t>();
          p.peak_box_z = f[2].cast<double>();
          p.max_abs_box_y = f[3].cast<double>();
          p.final_box_x = f[4].cast<double>();
          p.final_box_y = f[5].cast<double>();
          p.final_box_z = f[6].cast<double>();
          p.final_pusher_x = f[7].cast<double>();
          p.warnings = f[8].cast<int>();
          const auto e = f[9].cast<std::array<double, 8>>();
          p.energy = {e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7]};
          result.points.push_back(p);
        }
        simloop::judge_sweep(result);
        return result;
      },
      "duration"_a, "points"_a);
  m.def("sweep_steps", &simloop::sweep_steps, "duration"_a, "timestep"_a);
  m.def("check_scenario", &simloop::check_scenario, "scene"_a, "scenario"_a, "config"_a,
        "Everything run_scenario checks before its first step, without running.");

  // Policies and episodes (the training code's side): a policy decides ctrl
  // every `control_every` steps of a scenario run; Episodes steps N runs of a
  // scenario from outside, one decision at a time (Gymnasium).
  m.def(
      "run_scenario_policy",
      [](const simloop::Model& scene, const simloop::Scenario& scenario, const simloop::ScenarioConfig& config,
         py::object decide, std::int64_t control_every, py::object progress) {
        PyPolicy policy(std::move(decide), control_every);
        Interruptible work(std::move(progress));
        simloop::ScenarioRunResult result = work.run([&](simloop::RunControl* control) {
          return naming_failures("run_scenario(" + scenario.name + ", policy=...)", [&] {
            return simloop::run_scenario(scene, scenario, config, nullptr, nullptr, control, simloop::RunInputs::deciding(policy));
          });
        });
        work.finish();
        return result;
      },
      "scene"_a, "scenario"_a, "config"_a, "decide"_a, "control_every"_a, "progress"_a = py::none());
  m.def(
      "run_scenario_batch_policy",
      [](const simloop::Model& scene, const simloop::Scenario& scenario,
         const std::vector<simloop::ScenarioConfig>& configs, int threads, py::object decide,
         std::int64_t control_every, py::object progress) {
        PyPolicy policy(std::move(decide), control_every);
        Interruptible work(std::move(progress));
        std::vector<simloop::ScenarioRunResult> results = work.run([&](simloop::RunControl* control) {
          return naming_failures(
              "run_scenario_batch(" + scenario.name + ", policy=...) x " + std::to_string(configs.size()) + " runs",
              [&] { return simloop::run_scenario_batch(scene, scenario, configs, threads, control,
                                              std::vector<simloop::RunInputs>(configs.size(), simloop::RunInputs::deciding(policy))); });
        });
        work.finish();
        return results;
      },
      "scene"_a, "scenario"_a, "configs"_a, "threads"_a, "decide"_a, "control_every"_a, "progress"_a = py::none());

  // Observations live in one (count, width) buffer the Python side reads
  // after each call (copied out: a returned array never changes later).
  struct PyEpisodes {
    PyEpisodes(const simloop::Model& scene, const simloop::Scenario& scenario, const simloop::ScenarioConfig& config,
               std::size_t count)
        : episodes(scene, scenario, config, count),
          observations(static_cast<std::size_t>(episodes.width()) * count, 0.0) {}
    simloop::Episodes episodes;
    std::vector<double> observations;
    std::mutex mutex;  // one call at a time (the GIL is released while stepping)
  };
  py::class_<PyEpisodes>(m, "Episodes", "N episodes of a scenario, stepped a decision at a time (gym.py).")
      .def(py::init([](const simloop::Model& scene, const simloop::Scenario& scenario,
                       const simloop::ScenarioConfig& config, std::size_t count) {
             return naming_failures("Episodes", [&] { return std::make_unique<PyEpisodes>(scene, scenario, config, count); });
           }),
           "scene"_a, "scenario"_a, "config"_a, "count"_a)
      .def_property_readonly("count", [](PyEpisodes& e) { return e.episodes.count(); })
      .def_property_readonly("nu", [](PyEpisodes& e) { return e.episodes.nu(); })
      .def_property_readonly("steps", [](PyEpisodes& e) { return e.episodes.steps(); })
      .def_property_readonly("timestep", [](PyEpisodes& e) { return e.episodes.model().timestep(); })
      .def_property_readonly("column_names",
                             [](PyEpisodes& e) {
                               py::tuple names(e.episodes.columns().size());
                               for (size_t i = 0; i < e.episodes.columns().size(); ++i) {
                                 names[i] = py::str(e.episodes.columns()[i].name);
                               }
                               return names;
                             })
      .def_property_readonly("ctrl_range",
                             [](PyEpisodes& e) {
                               const simloop::CtrlRange r = simloop::ctrl_range(e.episodes.model().get());
                               return py::make_tuple(vec(r.low.data(), r.low.size()), vec(r.high.data(), r.high.size()));
                             })
      .def(
          "reset",
          [](PyEpisodes& e, std::size_t i, std::uint64_t seed) {
            std::lock_guard<std::mutex> lock(e.mutex);
            const auto width = static_cast<std::size_t>(e.episodes.width());
            if (i >= e.episodes.count()) {
              throw py::index_error("episode " + std::to_string(i) + " does not exist: there are " +
                                    std::to_string(e.episodes.count()));
            }
            e.episodes.reset(i, seed, e.observations.data() + i * width);
            return vec(e.observations.data() + i * width, width);
          },
          "i"_a, "seed"_a)
      .def(
          "step",
          [](PyEpisodes& e, const py::array_t<double, py::array::c_style | py::array::forcecast>& actions,
             std::int64_t every, const std::optional<py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>>& active,
             int threads) {
            std::lock_guard<std::mutex> lock(e.mutex);
            const std::size_t n = e.episodes.count();
            const auto width = static_cast<py::ssize_t>(e.episodes.width());
            if (static_cast<std::size_t>(actions.size()) != n * static_cast<std::size_t>(e.episodes.nu())) {
              throw py::value_error("actions must hold " + std::to_string(n) + " x " + std::to_string(e.episodes.nu()) +
                                    " values, got " + std::to_string(actions.size()));
            }
            if (active && static_cast<std::size_t>(active->size()) != n) {
              throw py::value_error("active must hold " + std::to_string(n) + " flags");
            }
            std::vector<std::uint8_t> terminated(n, 0), truncated(n, 0);
            const std::uint8_t* mask = active ? active->data() : nullptr;
            const auto work_steps = every > 0 ? static_cast<double>(every) * static_cast<double>(n) : 0.0;
            const auto stepping = [&](simloop::RunControl* control) {
              e.episodes.step(actions.data(), every, mask, e.observations.data(), terminated.data(), truncated.data(),
                              threads, control);
            };
            if (work_steps <= static_cast<double>(simloop::RunControl::kChunkSteps)) {
              py::gil_scoped_release release;  // nothing long to interrupt
              stepping(nullptr);
            } else {
              Interruptible work{py::none()};
              work.run(stepping);
            }
            py::array_t<double> observations({static_cast<py::ssize_t>(n), width});
            std::copy(e.observations.begin(), e.observations.end(), observations.mutable_data());
            py::array_t<bool> term(static_cast<py::ssize_t>(n)), trunc(static_cast<py::ssize_t>(n));
            std::copy(terminated.begin(), terminated.end(), term.mutable_data());
            std::copy(truncated.begin(), truncated.end(), trunc.mutable_data());
            return py::make_tuple(observations, term, trunc);
          },
          "actions"_a, "every"_a, "active"_a = py::none(), "threads"_a = 1)
      .def("steps_taken", [](PyEpisodes& e, std::size_t i) { return e.episodes.steps_taken(i); }, "i"_a)
      .def("time", [](PyEpisodes& e, std::size_t i) { return e.episodes.time(i); }, "i"_a)
      .def("warnings", [](PyEpisodes& e, std::size_t i) { return e.episodes.warnings(i); }, "i"_a);
}
