// simloop._core's command: python -m simloop takes sim_loop's own
// orchestration (command/command.cc) step by step (simloop.__main__), with
// its report through sys.stdout, its progress bar, and its recording drawn
// from the rows the run kept. The orchestration calls no Python.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <filesystem>
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

}  // namespace

void bind_command(py::module_& m) {
  // A failure as the command reports it: args (exit code, line).
  static py::exception<cli::Failure> failure(m, "CommandFailure", PyExc_Exception);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const cli::Failure& e) {
      PyErr_SetObject(failure.ptr(), py::make_tuple(e.code, fs_str(e.what())).ptr());
    }
  });
  m.attr("MAX_BATCH_RUNS") = cli::kMaxBatchRuns;
  m.attr("MAX_CHUNK_RUNS") = cli::kMaxChunkRuns;
  // `batch`'s flags, as python -m simloop batch takes them: None where the
  // command's default (or the scenario's) applies.
  py::class_<cli::BatchOptions>(m, "BatchCommandLine")
      .def_property_readonly("scenario",
                             [](const cli::BatchOptions& b) -> py::object {
                               return b.scenario.empty() ? py::none() : py::object(fs_str(b.scenario));
                             })
      .def_property_readonly("seeds",
                             [](const cli::BatchOptions& b) {
                               py::list seeds;  // at most kMaxBatchRuns
                               for (const cli::SeedRange& r : b.seeds) {
                                 for (std::uint64_t s = r.first;; s += r.step) {
                                   seeds.append(s);
                                   if (r.last - s < r.step) break;  // (s + step may pass 2^64-1)
                                 }
                               }
                               return seeds;
                             })
      .def_readonly("timesteps", &cli::BatchOptions::timesteps)
      .def_property_readonly("params",
                             [](const cli::BatchOptions& b) {
                               py::list params;
                               for (const cli::BatchParam& p : b.params) {
                                 params.append(py::make_tuple(p.kind, fs_str(p.name), p.values));
                               }
                               return params;
                             })
      .def_property_readonly(
          "steps", [](const cli::BatchOptions& b) { return b.steps ? py::cast(b.steps) : py::object(py::none()); })
      .def_property_readonly("rng", [](const cli::BatchOptions& b) { return fs_str(b.rng); })
      .def_readonly("perturb", &cli::BatchOptions::perturb)
      .def_property_readonly("scheduler",
                             [](const cli::BatchOptions& b) -> py::object {
                               return b.scheduler.empty() ? py::none() : py::object(fs_str(b.scheduler));
                             })
      .def_property_readonly(
          "threads",
          [](const cli::BatchOptions& b) { return b.threads ? py::cast(b.threads) : py::object(py::none()); })
      .def_property_readonly(
          "chunk_size",
          [](const cli::BatchOptions& b) { return b.chunk_size ? py::cast(b.chunk_size) : py::object(py::none()); })
      .def_property_readonly("out", [](const cli::BatchOptions& b) { return fs_str(b.out.native()); })
      .def_readonly("resume", &cli::BatchOptions::resume);
  // The command line, parsed by sim_loop's own parser, as the recording reads it.
  py::class_<cli::Options>(m, "CommandLine")
      .def_readonly("batch", &cli::Options::batch)
      .def_readonly("sweep_timesteps", &cli::Options::sweep_timesteps)
      .def_readonly("run", &cli::Options::run)
      .def_readonly("rerun", &cli::Options::rerun)
      .def_readonly("plot", &cli::Options::plot)
      .def_readonly("plot_what", &cli::Options::plot_what)
      .def_property_readonly("plot_compare",
                             [](const cli::Options& o) {
                               py::list paths;
                               for (const auto& p : o.plot_compare) paths.append(fs_str(p.native()));
                               return paths;
                             })
      .def_readonly("plot_x", &cli::Options::plot_x)
      .def_readonly("help", &cli::Options::help)
      .def_readonly("version", &cli::Options::version)
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
  py::class_<cli::Orchestration>(m, "Orchestration", "sim_loop's orchestration, step by step (command.hpp).")
      .def(py::init([](const std::vector<py::object>& args) {
             return std::make_unique<cli::Orchestration>(argument_bytes(args));
           }),
           "args"_a)
      .def_property_readonly("options", &cli::Orchestration::options, py::return_value_policy::reference_internal)
      .def_property_readonly("sweep", &cli::Orchestration::sweep)
      .def_static("banner", [] { return fs_str(cli::Orchestration::banner()); })
      .def("load", [](cli::Orchestration& o) { return fs_str(o.load()); })
      .def("check", &cli::Orchestration::check)
      .def("open_output", &cli::Orchestration::open_output)
      .def(
          "run",
          [](cli::Orchestration& o, py::object progress, bool drawn) {
            Interruptible work(std::move(progress));
            work.run([&](simloop::RunControl* control) {
              o.run(control, drawn);
              return 0;
            });
            work.finish();
          },
          "progress"_a, "drawn"_a)
      .def(
          "commit",
          [](cli::Orchestration& o, const std::vector<simloop::PipedFile*>& also) {
            o.commit(nullptr, pending_files(also));
          },
          "also"_a)
      .def_property_readonly("committed", &cli::Orchestration::committed)
      .def_property_readonly("model", [](const cli::Orchestration& o) { return o.model(); })
      .def_property_readonly(
          "scenario", [](const cli::Orchestration& o) { return o.scenario() ? py::cast(*o.scenario()) : py::none(); })
      .def_property_readonly("result",
                             [](const cli::Orchestration& o) {
                               if (o.chapter_result()) return py::cast(*o.chapter_result());
                               return o.scenario_result() ? py::cast(*o.scenario_result()) : py::none();
                             })
      .def("drawn_columns", [](cli::Orchestration& o) { return o.drawn_rows()->names(); })
      .def("next_drawn_block",
           [](cli::Orchestration& o) -> py::object {
             std::vector<double> rows;
             if (!o.drawn_rows()->next(rows)) return py::none();
             const auto columns = static_cast<py::ssize_t>(o.drawn_rows()->columns());
             py::array_t<double> block(
                 {static_cast<py::ssize_t>(rows.size()) / std::max<py::ssize_t>(columns, 1), columns});
             std::copy(rows.begin(), rows.end(), block.mutable_data());
             return std::move(block);
           })
      .def(
          "report", [](const cli::Orchestration& o, const py::str& drawn) { return fs_str(o.report(fs_bytes(drawn))); },
          "drawn"_a)
      .def_static(
          "plot_line", [](const py::str& png) { return fs_str(cli::Orchestration::plot_line(fs_bytes(png))); }, "png"_a)
      .def("closing_line", &cli::Orchestration::closing_line)
      .def_property_readonly("doing", [](const cli::Orchestration& o) { return fs_str(o.doing()); })
      .def("close", &cli::Orchestration::close);
  m.def("help_text", &simloop::cli::help_text, "program"_a, "recording"_a);
  m.def("_peak_memory_mib", &cli::peak_memory_mib, "VmHWM of this process, MiB (-1 if unknown): the report's.");
  m.def(
      "_one_line", [](const py::bytes& text) { return py::bytes(simloop::one_line(std::string(text))); }, "text"_a,
      "A message's bytes on one line, control characters as \\xNN.");
  m.def("sweep_help_text", &simloop::cli::sweep_help_text, "program"_a);
}

}  // namespace simloop_py
