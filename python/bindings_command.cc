// simloop._core's command: python -m simloop runs sim_loop's own
// orchestration (command/command.cc) with a Python host: its report through
// sys.stdout, its progress bar, its recording and its plot (simloop.__main__).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bindings_common.hpp"
#include "cli_options.hpp"
#include "command.hpp"
#include "simloop/model.hpp"
#include "simloop/piped_file.hpp"
#include "simloop/scenario.hpp"

namespace simloop_py {
namespace {

using namespace pybind11::literals;
namespace cli = simloop::cli;

// Arguments as the shell passed them: a str encoded back to its bytes (as
// os.fsencode does; sys.argv carries undecodable bytes as surrogates), or bytes.
std::vector<std::string> argument_bytes(const std::vector<py::object>& args) {
  std::vector<std::string> bytes;
  for (const py::object& a : args) {
    PyObject* encoded = PyUnicode_Check(a.ptr()) ? PyUnicode_EncodeFSDefault(a.ptr()) : nullptr;
    if (PyUnicode_Check(a.ptr()) && !encoded) throw py::error_already_set();
    const py::object raw = encoded ? py::reinterpret_steal<py::object>(encoded) : a;
    if (!PyBytes_Check(raw.ptr())) throw py::type_error("command line arguments must be str or bytes");
    bytes.emplace_back(PyBytes_AS_STRING(raw.ptr()), static_cast<size_t>(PyBytes_GET_SIZE(raw.ptr())));
  }
  return bytes;
}

// Python text as the bytes it stands for (os.fsencode: a path's undecodable
// bytes come back as they were).
std::string fs_bytes(const py::handle& text) {
  return py::module_::import("os").attr("fsencode")(py::str(text)).cast<std::string>();
}

// The rows of a run handed to Python as they come (for a recording made
// while the run streams its files): `to.columns(names)` once, then
// `to.rows(array)` per block, each a (rows, columns) float64 copy, and
// `to.finish(result)` once the run is done (before its outputs are put in
// place), called with the GIL. An exception there stops the run and reaches
// the caller (raise_if_failed, once the run is over).
class RowsToPython final : public simloop::RowSink {
 public:
  struct Failed {};
  explicit RowsToPython(py::object to) : to_(std::move(to)) {}
  ~RowsToPython() override {
    py::gil_scoped_acquire gil;
    to_ = py::object();
    error_.reset();
  }
  void describe(const std::vector<simloop::Column>& columns) override {
    call([&] {
      py::list names;
      for (const simloop::Column& c : columns) names.append(c.name);
      to_.attr("columns")(names);
    });
  }
  void start(int columns, std::int64_t /*rows*/) override { columns_ = columns; }
  void write(const double* rows, std::int64_t count) override {
    call([&] {
      py::array_t<double> block({static_cast<py::ssize_t>(count), static_cast<py::ssize_t>(columns_)});
      std::copy(rows, rows + count * columns_, block.mutable_data());
      to_.attr("rows")(block);
    });
  }
  template <class Result>
  void finish(const Result& result) {
    call([&] { to_.attr("finish")(py::cast(result)); });
  }
  void raise_if_failed() {
    if (!error_) return;
    py::error_already_set error = std::move(*error_);
    error_.reset();
    throw error;
  }

 private:
  template <class Call>
  void call(Call&& c) {
    py::gil_scoped_acquire gil;
    try {
      c();
    } catch (py::error_already_set& e) {
      error_.emplace(std::move(e));
      throw Failed{};
    }
  }
  py::object to_;
  int columns_ = 0;
  std::optional<py::error_already_set> error_;
};

// The recording a Python host made: its rows go to recording.columns/rows,
// finish(result) to recording.finish, its files are recording.files.
class PyRecording final : public cli::Recording {
 public:
  PyRecording(py::object recording, std::string line)
      : recording_(recording), rows_(std::move(recording)), line_(std::move(line)) {}
  ~PyRecording() override {
    py::gil_scoped_acquire gil;
    try {
      recording_.attr("close")();       // abandons the file unless it was finished
    } catch (py::error_already_set&) {  // a destructor cannot raise; the run's own error is what matters
    }
    recording_ = py::object();
  }
  simloop::RowSink& rows() override { return rows_; }
  std::vector<simloop::PendingFile*> files() override {
    py::gil_scoped_acquire gil;
    std::vector<simloop::PendingFile*> files;
    for (const py::handle f : recording_.attr("files")) files.push_back(&f.cast<simloop::PipedFile*>()->pending());
    return files;
  }
  void finish(const simloop::RunResult& result) override { rows_.finish(result); }
  void finish(const simloop::RunRecord& result) override { rows_.finish(result); }
  [[nodiscard]] std::string line() const override { return line_; }
  void raise_if_failed() { rows_.raise_if_failed(); }

 private:
  py::object recording_;
  RowsToPython rows_;
  std::string line_;
};

// The host: simloop.__main__._Host's methods. What Python raises in the
// recording, the progress or the plot becomes the command's one line
// (host.Failure with its exit code; OSError and ValueError, exit 1);
// anything else (KeyboardInterrupt, a lost report) passes through as itself.
class PyHost final : public cli::Host {
 public:
  explicit PyHost(py::object host) : host_(std::move(host)) {}

  [[nodiscard]] std::string help(bool sweep) const override { return host_.attr("help")(sweep).cast<std::string>(); }
  [[nodiscard]] std::string version() const override { return host_.attr("version")().cast<std::string>(); }
  void print(std::string_view text) override { host_.attr("print")(fs_str(std::string(text))); }
  void flush() override { host_.attr("flush")(); }
  int fail(int code, const std::string& line) override { return host_.attr("fail")(code, fs_str(line)).cast<int>(); }
  void work(const char* label, const std::function<void(simloop::RunControl*)>& work) override {
    converting([&] {
      py::object bar = host_.attr("progress")(label);
      Interruptible run(bar.attr("__enter__")());
      try {
        run.run([&](simloop::RunControl* control) {
          work(control);
          return 0;
        });
        run.finish();
      } catch (const RowsToPython::Failed&) {
        bar.attr("__exit__")(py::none(), py::none(), py::none());
        if (recording_) recording_->raise_if_failed();
        throw;
      } catch (...) {
        bar.attr("__exit__")(py::none(), py::none(), py::none());
        throw;
      }
      bar.attr("__exit__")(py::none(), py::none(), py::none());
    });
  }
  void outputs_written() override { host_.attr("outputs_written")(); }
  std::unique_ptr<cli::Recording> recording(const cli::Options& opts, const simloop::Model& model,
                                            const simloop::Scenario* scenario) override {
    std::unique_ptr<PyRecording> made;
    converting([&] {
      const py::object made_here = host_.attr("recording")(opts, model, scenario ? py::cast(*scenario) : py::none());
      if (made_here.is_none()) return;
      const auto [recording, line] = made_here.cast<std::pair<py::object, py::object>>();
      made = std::make_unique<PyRecording>(recording, fs_bytes(line));
    });
    recording_ = made.get();
    return made;
  }
  std::filesystem::path plot(const std::filesystem::path& out, const char* what) override {
    std::filesystem::path png;
    converting([&] { png = host_.attr("plot")(fs_str(out.string()), what).cast<std::filesystem::path>(); });
    return png;
  }
  int interrupted() override {
    PyErr_SetNone(PyExc_KeyboardInterrupt);
    throw py::error_already_set();
  }
  [[nodiscard]] bool passes_through(const std::exception_ptr& error) const override {
    try {
      std::rethrow_exception(error);
    } catch (const py::error_already_set&) {
      return true;
    } catch (...) {
      return false;
    }
  }

 private:
  template <class Call>
  void converting(Call&& call) {
    try {
      call();
    } catch (py::error_already_set& e) {
      if (e.matches(host_.attr("Failure"))) {
        throw cli::Failure(e.value().attr("code").cast<int>(), fs_bytes(e.value()));
      }
      if (e.matches(PyExc_OSError) || e.matches(PyExc_ValueError)) {
        throw cli::Failure(cli::kExitRunFailed, fs_bytes(e.value()));
      }
      if (e.matches(PyExc_MemoryError)) throw std::bad_alloc();
      throw;
    }
  }

  py::object host_;
  PyRecording* recording_ = nullptr;  // the run's, while it lives
};

}  // namespace

void bind_command(py::module_& m) {
  // The command line, parsed by sim_loop's own parser, as the host's recording reads it.
  py::class_<cli::Options>(m, "CommandLine")
      .def_readonly("sweep_timesteps", &cli::Options::sweep_timesteps)
      .def_readonly("run", &cli::Options::run)
      .def_readonly("rerun", &cli::Options::rerun)
      .def_property_readonly("video", [](const cli::Options& o) { return fs_str(o.video.native()); })
      // Paths as Python spells file names: undecodable bytes as surrogates.
      .def_property_readonly("out", [](const cli::Options& o) { return fs_str(o.out.native()); })
      .def_property_readonly("model_path", [](const cli::Options& o) { return fs_str(o.model_path); })
      .def_property_readonly("scenario_path", [](const cli::Options& o) { return fs_str(o.scenario_path); });
  // args: str (sys.argv's, encoded back to the bytes the shell passed, as
  // os.fsencode does) or bytes.
  m.def("parse_command_line", [](const std::vector<py::object>& args) {
    try {
      return cli::parse(argument_bytes(args));
    } catch (const cli::UsageError& e) {
      set_error_fs(PyExc_ValueError, e.what());
      throw py::error_already_set();
    }
  });
  m.def(
      "run_command",
      [](const std::vector<py::object>& args, py::object host) {
        PyHost python_host(std::move(host));
        return cli::run_command(argument_bytes(args), python_host);
      },
      "args"_a, "host"_a,
      "sim_loop's whole command with `host` (simloop.__main__'s) doing the process's part: returns the exit code.");
  m.def("help_text", &simloop::cli::help_text, "program"_a, "recording"_a);
  m.def("_peak_memory_mib", &cli::peak_memory_mib, "VmHWM of this process, MiB (-1 if unknown): the report's.");
  m.def(
      "_one_line", [](const py::bytes& text) { return py::bytes(simloop::one_line(std::string(text))); }, "text"_a,
      "A message's bytes on one line, control characters as \\xNN.");
  m.def("sweep_help_text", &simloop::cli::sweep_help_text, "program"_a);
}

}  // namespace simloop_py
