// simloop._core's command line: python -m simloop parses its flags with
// sim_loop's own parser (command/cli_options) and reuses its checks.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <string>
#include <vector>

#include "bindings_common.hpp"
#include "cli_options.hpp"
#include "simloop/model.hpp"
#include "simloop/output.hpp"
#include "simloop/scenario.hpp"

namespace simloop_py {

using namespace pybind11::literals;

void bind_command(py::module_& m) {
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
}

}  // namespace simloop_py
