// What the binding files share: long C++ work that Ctrl-C can stop
// (Interruptible), the standard library's resource failures said with what
// was being done, and the conversions several topics use.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "simloop/call_gate.hpp"
#include "simloop/control.hpp"
#include "simloop/number_format.hpp"
#include "simloop/output.hpp"
#include "simloop/piped_file.hpp"
#include "simloop/record_bytes.hpp"
#include "simloop/run.hpp"

namespace simloop_py {

namespace py = pybind11;

// The standard library's resource failures, said with what was being done
// (pybind11 alone would say "std::bad_alloc"). Raised as MemoryError and
// RuntimeError.
class OutOfMemory : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
class ResourceFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

template <class Work>
auto naming_failures(const std::string& what, Work&& work) -> decltype(work()) {
  try {
    return work();
  } catch (const std::bad_alloc&) {
    throw OutOfMemory(what + ": out of memory");
  } catch (const std::system_error& e) {
    throw ResourceFailure(what + ": " + e.what());
  }
}

// Python's signal handlers, run between the chunks of long work and the
// slices of a long wait, so that Ctrl-C and SIGTERM act during them.
inline void check_signals() {
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
}

// Long C++ work that Ctrl-C can stop: the work runs with the GIL released,
// and its RunControl's poll (on this thread, at most every 20 ms) takes the
// GIL to run the signal handlers and progress(steps_done, steps_total). What
// they raise stops the work and reaches the caller (RunControl::run). Python
// runs signal handlers only on the main thread: elsewhere, without a
// progress callback, there is nothing to poll and the GIL is left alone.
class Interruptible {
 public:
  explicit Interruptible(py::object progress)
      : progress_(progress.is_none() ? py::object() : std::move(progress)),
        control_(progress_ || on_main_thread()
                     ? simloop::RunControl::Poll([this](std::int64_t done, std::int64_t total) {
                         py::gil_scoped_acquire gil;
                         check_signals();
                         if (progress_) progress_(done, total);
                       })
                     : simloop::RunControl::Poll()) {}

  template <class Work>
  auto run(Work&& work) -> decltype(work(static_cast<simloop::RunControl*>(nullptr))) {
    return control_.run([&](simloop::RunControl* control) {
      py::gil_scoped_release release;
      return work(control);
    });
  }

  // After the work is done: one last progress call, at its full count.
  void finish() {
    if (progress_) progress_(control_.steps_done(), control_.steps_total());
  }

 private:
  static bool on_main_thread() {
    return py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>() ==
           PyThread_get_thread_ident();
  }
  py::object progress_;
  simloop::RunControl control_;
};

// A wait in slices (simloop::wait_in_slices) with the GIL released during
// each: False if `timeout` seconds pass first.
template <class WaitSlice>
bool wait_without_gil(WaitSlice&& wait_slice, std::optional<double> timeout = std::nullopt) {
  return simloop::wait_in_slices(
      [&](std::chrono::milliseconds slice) {
        py::gil_scoped_release release;
        return wait_slice(slice);
      },
      check_signals, timeout);
}

// Text from the C++ side that may hold a path's raw bytes (not UTF-8): as a
// str the way Python decodes file names (os.fsdecode, surrogateescape).
inline py::str fs_str(const std::string& text) {
  PyObject* decoded = PyUnicode_DecodeFSDefaultAndSize(text.data(), static_cast<py::ssize_t>(text.size()));
  if (!decoded) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(decoded);
}

// Sets a Python error whose message is `what` on one line (MuJoCo's own
// messages can span several), decoded as fs_str does (bindings_args.cc).
void set_error_fs(PyObject* type, const char* what);

inline py::array vec(const double* values, size_t n) {
  return py::array_t<double>(static_cast<py::ssize_t>(n), values);
}
inline py::array vector_array(const std::vector<double>& values) { return vec(values.data(), values.size()); }
inline std::string py_bool(bool b) { return b ? "True" : "False"; }
inline std::string py_str_repr(const std::string& text) { return py::repr(py::str(text)).cast<std::string>(); }

// A generator by its name, as every config's rng= takes it (ValueError for
// any other).
inline simloop::ShoveRng shove_rng(const std::string& name) { return simloop::rng_named(name); }

// __repr__ as Name(field=value, ...), each field read back as the object's
// Python attribute and spelled by repr(): a repr agrees with what it shows.
inline auto fields_repr(std::string name, std::vector<const char*> fields) {
  return [name = std::move(name), fields = std::move(fields)](const py::object& self) {
    std::string out = name + "(";
    for (const char* f : fields) {
      out += std::string(f == fields.front() ? "" : ", ") + f + "=" + py::repr(self.attr(f)).cast<std::string>();
    }
    return out + ")";
  };
}

// A view numpy must not let Python write through (what MuJoCo derives, or
// a finished run's rows).
inline py::array read_only(py::array view) {
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

// A long call: Ctrl-C stops it within a chunk of steps (Interruptible);
// progress(steps_done, steps_total), if given, is called from this thread at
// most every 20 ms, and once at the end; `what` names the call in a
// resource failure's message.
template <class Work>
auto long_call(py::object progress, const std::string& what, Work&& work) {
  Interruptible call(std::move(progress));
  auto result =
      call.run([&](simloop::RunControl* control) { return naming_failures(what, [&] { return work(control); }); });
  call.finish();
  return result;
}

// Python arguments as C++ values, or a one-line TypeError or ValueError
// naming the argument (bindings_args.cc; simloop._checks uses them too).
std::string show(const py::handle& value);
std::string describe(const py::handle& value);
py::str check_path(const std::string& name, const py::handle& value, const std::string& what);
py::bytes check_text(const std::string& name, const py::handle& value);
double check_real(const std::string& name, const py::handle& value);
inline std::filesystem::path path_arg(const std::string& name, const py::handle& value, const std::string& what) {
  return py::cast<std::filesystem::path>(check_path(name, value, what));
}
// A method that takes no arguments, answering extra ones in Python's own
// one line (pybind11's TypeError would list the signature over several).
template <class Result, std::string (*Text)(const Result&)>
auto no_arguments(std::string method) {
  return [method = std::move(method)](const Result& r, const py::args& extra) {
    if (!extra.empty()) {
      throw py::type_error(method + "() takes 1 positional argument but " + std::to_string(extra.size() + 1) +
                           " were given");
    }
    return Text(r);
  };
}

// result.write(out): metrics.json and trajectory.csv into out, as
// simloop::write_outputs writes them for this kind of result.
template <class Result>
std::pair<std::filesystem::path, std::filesystem::path> write_result(const Result& r, const py::object& out_arg) {
  const std::filesystem::path out = path_arg("out", out_arg, "a directory");
  py::gil_scoped_release release;
  const simloop::OutputFiles files =
      naming_failures("write(" + out.string() + ")", [&] { return simloop::write_outputs(r, out); });
  return {files.metrics, files.trajectory};
}

// The finished files (PipedFile, from Python's list) to put in place with a
// run's own; ValueError for a None among them.
inline std::vector<simloop::PendingFile*> pending_files(const std::vector<simloop::PipedFile*>& also) {
  std::vector<simloop::PendingFile*> files;
  for (simloop::PipedFile* f : also) {
    if (f == nullptr) throw py::value_error("also: None is not a PipedFile");
    files.push_back(&f->pending());
  }
  return files;
}

// py::pickle for a result: the library's bytes (record_bytes.hpp) and back.
// A state that is not bytes (the (version, fields) tuples of pickle format 3)
// reads as no bytes: refused as damaged or from another simloop version.
template <class Result, Result (*Read)(std::string_view)>
auto pickle_as_bytes() {
  return py::pickle([](const Result& r) -> py::object { return py::bytes(simloop::to_bytes(r)); },
                    [](const py::object& state) {
                      if (!py::isinstance<py::bytes>(state)) return Read({});
                      return Read(state.cast<py::bytes>());
                    });
}

// What every kind of sweep result offers beside its own figures: its edge,
// sweep.csv, the table for people, writing sweep.csv, and its repr.
template <class Result, std::string (*Csv)(const Result&), std::string (*Summary)(const Result&)>
void bind_sweep_outputs(py::class_<Result>& result, const char* edge_doc) {
  result
      .def_property_readonly(
          "edge",
          [](const Result& r) -> py::object {
            if (r.edge_index < 0) return py::none();
            return py::float_(r.points[static_cast<size_t>(r.edge_index)].timestep);
          },
          edge_doc)
      .def("csv", no_arguments<Result, Csv>(py::str(result.attr("__name__")).cast<std::string>() + ".csv"),
           "sweep.csv's text.")
      .def("summary", no_arguments<Result, Summary>(py::str(result.attr("__name__")).cast<std::string>() + ".summary"),
           "The sweep's table, edge and criterion.")
      .def(
          "write",
          [](const Result& r, const py::object& out_arg) {
            const std::filesystem::path out = path_arg("out", out_arg, "a directory");
            simloop::prepare_output_dir(out);
            simloop::write_file_atomically(out / "sweep.csv", Csv(r));
            return out / "sweep.csv";
          },
          py::arg("out"), "Writes sweep.csv into out (atomically); returns its path.")
      .def("__repr__", [](const py::object& self) {
        const Result& r = self.cast<const Result&>();
        std::string text = py::str(py::type::handle_of(self).attr("__name__")).cast<std::string>() + "(";
        if (py::hasattr(self, "name")) text += "name=" + py::repr(self.attr("name")).cast<std::string>() + ", ";
        text += "points=" + std::to_string(r.points.size());
        if (!r.points.empty()) {
          text += ", timesteps=" + simloop::python_float_repr(r.points.front().timestep) + ".." +
                  simloop::python_float_repr(r.points.back().timestep);
        }
        return text + ", duration=" + simloop::python_float_repr(r.duration) +
               ", edge=" + py::repr(self.attr("edge")).cast<std::string>() + ")";
      });
}

// The topics' bindings, in the order bindings.cc registers them (a type is
// registered before any signature names it).
void bind_args(py::module_& m);
void bind_model(py::module_& m);
void bind_record(py::module_& m);
void bind_chapter(py::module_& m);
void bind_scenario(py::module_& m);
void bind_sim(py::module_& m);
void bind_render(py::module_& m);
void bind_command(py::module_& m);
void bind_outputs(py::module_& m);

}  // namespace simloop_py
