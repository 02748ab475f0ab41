// simloop._core's scenarios: a scenario, one run's config and result, runs
// and batches of them (the scenario's controls, the caller's arrays, or a
// policy's decisions), and a scenario swept over timesteps.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bindings_common.hpp"
#include "simloop/batch_table.hpp"
#include "simloop/model.hpp"
#include "simloop/number_format.hpp"
#include "simloop/output.hpp"
#include "simloop/recorder.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/scene_params.hpp"
#include "simloop/sweep.hpp"

namespace simloop_py {
namespace {

using namespace pybind11::literals;
using simloop::RunRecord;

// Python's arrays (made C-contiguous float64 by simloop.scenario_runs) as
// the library reads them, in place: the caller keeps them alive (they are
// this call's arguments) for the whole call.
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::optional<simloop::InputArray> input_array(const std::optional<DoubleArray>& array) {
  if (!array) return std::nullopt;
  return simloop::InputArray{array->data(), std::vector<std::int64_t>(array->shape(), array->shape() + array->ndim())};
}

// A batch's inputs: none, or each run's slice of the caller's arrays.
std::vector<simloop::RunInputs> batch_inputs(std::size_t runs, const std::optional<DoubleArray>& controls,
                                             const std::optional<DoubleArray>& initial_state) {
  if (!controls && !initial_state) return {};
  return simloop::split_inputs(runs, true, input_array(controls), input_array(initial_state));
}

// A Python callable as the loop's Policy: decide(step, row) -> ctrl, where
// row is the recorder's row (a fresh float64 array) and ctrl a float64
// vector (simloop/policy.py's wrapper turns the user's answer into one and
// adds the decision step to its exceptions; the loop checks its values).
// Called from whichever thread steps the run: it takes the GIL for the call.
class PyPolicy final : public simloop::Policy {
 public:
  PyPolicy(py::object decide, std::int64_t every) : Policy(every), decide_(std::move(decide)) {}
  ~PyPolicy() override {
    py::gil_scoped_acquire gil;
    decide_ = py::object();
  }
  PyPolicy(const PyPolicy&) = delete;
  PyPolicy& operator=(const PyPolicy&) = delete;

  void decide(std::int64_t step, const double* observation, int width, std::vector<double>& ctrl) override {
    py::gil_scoped_acquire gil;
    const DoubleArray out(decide_(step, py::array_t<double>(width, observation)));
    ctrl.assign(out.data(), out.data() + out.size());
  }

 private:
  py::object decide_;
};

}  // namespace

void bind_scenario(py::module_& m) {
  // One parser: the C++ one reads the TOML for both faces.
  py::class_<simloop::Scenario>(m, "Scenario",
                                "A scenario: scene, timestep, length, controls, disturbances, recording.")
      .def_static("chapter", &simloop::Scenario::chapter, "The chapter's run as a scenario.")
      .def_static(
          "from_file", [](const std::string& path) { return simloop::Scenario::from_toml_file(path); }, "path"_a)
      .def_static(
          "from_toml",
          [](const std::string& text, const std::string& source, const std::string& base, const std::string& name) {
            return simloop::Scenario::from_toml_string(text, source, base, name);
          },
          "text"_a, "source"_a = "<string>", "base"_a = "", "default_name"_a = "")
      .def_readonly("name", &simloop::Scenario::name)
      .def_property_readonly("scene", [](const simloop::Scenario& s) { return fs_str(s.scene.native()); })
      .def_readonly("timestep", &simloop::Scenario::timestep)
      .def_property_readonly(
          "csv_files",
          [](const simloop::Scenario& s) {
            py::list files;
            for (const auto& c : s.controls) {
              if (!c.csv.empty()) files.append(fs_str(c.csv.native()));
            }
            return files;
          },
          "The CSV files the controls were read from, in the file's order.")
      .def_property_readonly(
          "reset_params",
          [](const simloop::Scenario& s) {
            py::list params;
            for (const auto& p : s.reset.params)
              params.append(py::make_tuple(simloop::scene_param_kind_name(p.kind), p.name));
            return params;
          },
          "(kind, name) of each [[reset.param]]: the scene parameters each run draws at its reset.")
      .def("__repr__", [](const simloop::Scenario& s) {
        std::string length;
        switch (s.length.unit) {
          case simloop::When::Unit::kSteps:
            length = "steps=" + std::to_string(s.length.count);
            break;
          case simloop::When::Unit::kSeconds:
            length = "duration=" + simloop::python_float_repr(s.length.value);
            break;
          default:
            length = "length=" + simloop::python_float_repr(s.length.value);
            break;
        }
        std::string controls;
        for (const simloop::ControlSpec& c : s.controls)
          controls += (controls.empty() ? "" : ", ") + py_str_repr(c.actuator);
        std::string recorded;
        for (const std::string& b : s.record.bodies) recorded += (recorded.empty() ? "" : ", ") + py_str_repr(b);
        recorded = s.record.all_bodies ? "'all'" : "[" + recorded + "]";
        return "Scenario(name=" + py_str_repr(s.name) + ", scene=" +
               (s.scene.empty() ? std::string("None") : py::repr(fs_str(s.scene.native())).cast<std::string>()) +
               ", timestep=" + (s.timestep ? simloop::python_float_repr(*s.timestep) : std::string("None")) + ", " +
               length + ", controls=[" + controls + "], disturbances=" + std::to_string(s.disturbances.size()) +
               ", bodies=" + recorded + ")";
      });

  m.def("load_scene", &simloop::load_scene, "scenario"_a);
  m.def(
      "check_scenario_names",
      [](const simloop::Scenario& s, const simloop::Model& model) { (void)simloop::resolve(s, model.get()); },
      "scenario"_a, "model"_a);

  py::class_<simloop::ScenarioConfig>(m, "ScenarioConfig")
      .def(py::init([](std::uint64_t seed, const std::string& rng, std::optional<double> timestep,
                       std::optional<std::int64_t> steps, bool perturb, std::int64_t record_every, bool audit_energy) {
             return simloop::ScenarioConfig{seed, shove_rng(rng), timestep, steps, perturb, record_every, audit_energy};
           }),
           "seed"_a, "rng"_a, "timestep"_a, "steps"_a, "perturb"_a, "record_every"_a, "audit_energy"_a = false)
      .def("__repr__", [](const simloop::ScenarioConfig& c) {
        return "ScenarioConfig(seed=" + std::to_string(c.seed) + ", rng='" + std::string(simloop::rng_name(c.rng)) +
               "', timestep=" + (c.timestep ? simloop::python_float_repr(*c.timestep) : std::string("None")) +
               ", steps=" + (c.steps ? std::to_string(*c.steps) : std::string("None")) +
               ", perturb=" + py_bool(c.perturb) + ", record_every=" + std::to_string(c.record_every) +
               (c.audit_energy ? ", audit_energy=True)" : ")");
      });

  // A run, or a batch, follows the scenario's controls; or the caller's
  // (controls, initial_state: arrays simloop.scenario has checked and made
  // C-contiguous float64); or a policy's decisions (decide(step, row) -> ctrl,
  // every control_every steps). keep_rows false: metrics only.
  m.def(
      "run_scenario",
      [](const simloop::Model& scene, const simloop::Scenario& scenario, const simloop::ScenarioConfig& config,
         std::optional<DoubleArray> controls, std::optional<DoubleArray> initial_state, py::object decide,
         std::int64_t control_every, py::object progress) {
        simloop::RunInputs inputs =
            simloop::split_inputs(1, false, input_array(controls), input_array(initial_state)).front();
        std::optional<PyPolicy> policy;
        if (!decide.is_none()) inputs.policy = &policy.emplace(std::move(decide), control_every);
        const std::string what = "run_scenario(" + scenario.name + (policy ? ", policy=...)" : ")");
        return long_call(std::move(progress), what, [&](simloop::RunControl* control) {
          return simloop::run_scenario(scene, scenario, config, nullptr, nullptr, control, inputs);
        });
      },
      "scene"_a, "scenario"_a, "config"_a, "controls"_a = py::none(), "initial_state"_a = py::none(),
      "decide"_a = py::none(), "control_every"_a = 1, "progress"_a = py::none());
  m.def(
      "run_scenario_batch",
      [](const simloop::Model& scene, const simloop::Scenario& scenario,
         const std::vector<simloop::ScenarioConfig>& configs, int threads, std::optional<DoubleArray> controls,
         std::optional<DoubleArray> initial_state, py::object decide, std::int64_t control_every, bool keep_rows,
         py::object progress) {
        std::vector<simloop::RunInputs> inputs = batch_inputs(configs.size(), controls, initial_state);
        std::optional<PyPolicy> policy;
        if (!decide.is_none()) {
          inputs.assign(configs.size(), simloop::RunInputs::deciding(policy.emplace(std::move(decide), control_every)));
        }
        const std::string what = "run_scenario_batch(" + scenario.name + (policy ? ", policy=...)" : ")") + " x " +
                                 std::to_string(configs.size()) + " runs";
        return long_call(std::move(progress), what, [&](simloop::RunControl* control) {
          return simloop::run_scenario_batch(scene, scenario, configs, threads, control, inputs, keep_rows);
        });
      },
      "scene"_a, "scenario"_a, "configs"_a, "threads"_a, "controls"_a = py::none(), "initial_state"_a = py::none(),
      "decide"_a = py::none(), "control_every"_a = 1, "keep_rows"_a = true, "progress"_a = py::none());
  m.def(
      "run_scenario_table",
      [](const simloop::Model& scene, const simloop::Scenario& scenario,
         const std::vector<simloop::ScenarioConfig>& configs, int threads, std::optional<DoubleArray> controls,
         std::optional<DoubleArray> initial_state, py::object progress) {
        const std::vector<simloop::RunInputs> inputs = batch_inputs(configs.size(), controls, initial_state);
        const std::string what = "run_scenario_batch(" + scenario.name + ", metrics_only=True) x " +
                                 std::to_string(configs.size()) + " runs";
        return long_call(std::move(progress), what, [&](simloop::RunControl* control) {
          return simloop::run_scenario_table(scene, scenario, configs, threads, control, inputs);
        });
      },
      "scene"_a, "scenario"_a, "configs"_a, "threads"_a, "controls"_a = py::none(), "initial_state"_a = py::none(),
      "progress"_a = py::none(), "run_scenario_batch(keep_rows=False) reduced to its table, run by run.");
  m.def(
      "check_batch_inputs",
      [](std::size_t runs, std::optional<DoubleArray> controls, std::optional<DoubleArray> initial_state) {
        (void)simloop::split_inputs(runs, true, input_array(controls), input_array(initial_state));
      },
      "runs"_a, "controls"_a = py::none(), "initial_state"_a = py::none(),
      "What run_scenario_batch checks of its inputs' shapes against its runs, alone (before they go out in chunks).");
  m.def("check_scenario", &simloop::check_scenario, "scene"_a, "scenario"_a, "config"_a,
        "Everything run_scenario checks before its first step, without running.");
  m.def("scenario_columns", &simloop::scenario_columns, "scene"_a, "scenario"_a, "config"_a,
        "The names of the columns such a run records, after check_scenario's checks.");

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
      .def("__repr__", fields_repr("ScenarioSweepPoint", {"timestep", "blew_up"}));
  py::class_<simloop::ScenarioSweepResult> sweep_result(m, "ScenarioSweepResult", "A timestep sweep of a scenario.");
  bind_sweep_outputs<simloop::ScenarioSweepResult, &simloop::sweep_csv, &simloop::sweep_summary>(
      sweep_result, "The largest timestep before any blew up (None if even the finest did).");
  sweep_result.def_readonly("name", &simloop::ScenarioSweepResult::name)
      .def_readonly("duration", &simloop::ScenarioSweepResult::duration)
      .def_readonly("bodies", &simloop::ScenarioSweepResult::bodies)
      .def_readonly("scene_size", &simloop::ScenarioSweepResult::scene_size)
      .def_readonly("tolerance", &simloop::ScenarioSweepResult::tolerance)
      .def_readonly("points", &simloop::ScenarioSweepResult::points);
  m.def(
      "sweep_scenario",
      [](const simloop::Model& scene, const simloop::Scenario& scenario, const std::vector<double>& timesteps,
         double duration, const simloop::ScenarioConfig& config, int threads, py::object progress) {
        const std::string what = "sweep(scenario=" + scenario.name + ", " + std::to_string(timesteps.size()) +
                                 " timesteps, duration=" + simloop::python_float_repr(duration) + ")";
        return long_call(std::move(progress), what, [&](simloop::RunControl* control) {
          return simloop::sweep_scenario(scene, scenario, timesteps, duration, config, threads, control);
        });
      },
      "scene"_a, "scenario"_a, "timesteps"_a, "duration"_a, "config"_a, "threads"_a, "progress"_a = py::none());
  m.def("scenario_duration", &simloop::scenario_duration, "scene"_a, "scenario"_a);
  m.def("default_scenario_sweep_timesteps", &simloop::default_scenario_sweep_timesteps, "duration"_a);
  m.attr("SCENARIO_SWEEP_TOLERANCE") = simloop::kScenarioSweepTolerance;
}

}  // namespace simloop_py
