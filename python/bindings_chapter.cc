// simloop._core's chapter: its run's config, shove, result and batch, and
// Break It's sweep of the baseline over timesteps.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bindings_common.hpp"
#include "chapter_detail.hpp"
#include "simloop/model.hpp"
#include "simloop/number_format.hpp"
#include "simloop/output.hpp"
#include "simloop/run.hpp"
#include "simloop/shove.hpp"
#include "simloop/sweep.hpp"
#include "warning_counter.hpp"

namespace simloop_py {
namespace {

using namespace pybind11::literals;
using simloop::ChapterColumns;
using simloop::RunResult;

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

py::tuple column_names(int first, int end) {
  py::tuple names(static_cast<size_t>(end - first));
  for (int c = first; c < end; ++c) {
    names[static_cast<size_t>(c - first)] = py::str(std::string(ChapterColumns::kNames[c]));
  }
  return names;
}

std::string run_call(const char* name, const simloop::RunConfig& c) {
  return std::string(name) + "(steps=" + std::to_string(c.num_steps()) +
         ", record_every=" + std::to_string(c.record_every) + ")";
}

}  // namespace

void bind_chapter(py::module_& m) {
  m.attr("PUSHER_SCENE_XML") = std::string(simloop::pusher_scene_xml());
  m.attr("COLUMN_NAMES") = column_names(0, ChapterColumns::kNumBaseColumns);
  m.attr("ENERGY_COLUMN_NAMES") = column_names(ChapterColumns::kNumBaseColumns, ChapterColumns::kNumColumns);
  m.attr("SMOKE_STEPS") = simloop::kSmokeSteps;
  m.attr("SHOVE_STEPS") = simloop::kShoveSteps;
  m.attr("MAX_STEPS") = simloop::kMaxSteps;
  m.attr("MAX_RECORD_EVERY") = simloop::kMaxRecordEvery;
  m.attr("WARNING_NAMES") = py::tuple(py::cast(simloop::detail::all_warning_names()));

  py::class_<simloop::RunConfig>(m, "RunConfig")
      .def(py::init([](std::uint64_t seed, std::int64_t steps, double timestep, bool perturb, bool smoke,
                       std::int64_t record_every, bool audit_energy, const std::string& rng) {
             return simloop::RunConfig{seed,  steps,        timestep,     perturb,
                                       smoke, record_every, audit_energy, shove_rng(rng)};
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
      .def_readonly("record_every", &simloop::RunConfig::record_every)
      .def("__repr__", fields_repr("RunConfig", {"seed", "steps", "timestep", "perturb", "smoke", "record_every",
                                                 "audit_energy", "rng"}));

  py::class_<simloop::Shove>(m, "Shove", "The sideways shove drawn for a run (applied only if perturb).")
      .def_readonly("newtons", &simloop::Shove::newtons)
      .def_readonly("sign", &simloop::Shove::sign)
      .def_readonly("start_step", &simloop::Shove::start_step)
      .def_readonly("steps", &simloop::Shove::num_steps)
      .def_property_readonly("force_y", &simloop::Shove::force_y)
      .def_property_readonly(
          "rng", [](const simloop::Shove& s) { return std::string(simloop::rng_name(s.rng)); },
          "The generator that drew it: 'mt19937_64' or 'numpy'.")
      .def("__repr__", fields_repr("Shove", {"newtons", "sign", "start_step", "steps", "rng"}));
  m.def(
      "draw_shove",
      [](std::uint64_t seed, std::int64_t steps, const std::string& rng) {
        return simloop::draw_shove(seed, steps, shove_rng(rng));
      },
      "seed"_a, "steps"_a = 2000, "rng"_a = "mt19937_64", "The shove a run of `steps` steps draws from `seed`.");

  py::class_<RunResult, simloop::RunRecord>(
      m, "RunResult", "What the chapter's run did: its record (a ScenarioResult) with the chapter's report on top.")
      .def_property_readonly(
          "metrics", [](const RunResult& r) { return metrics_dict(r.metrics); },
          "The dict metrics.json holds (floats rounded to 6 decimals).")
      .def_property_readonly(
          "unrounded_metrics", [](const RunResult& r) { return metrics_dict(r.unrounded_metrics); },
          "metrics as computed, not rounded (metrics.json rounds to 6 decimals).")
      .def_readonly("shove", &RunResult::shove)
      .def_readonly("config", &RunResult::config)
      .def("metrics_json", no_arguments<RunResult, &simloop::metrics_json>("RunResult.metrics_json"),
           "metrics.json's text.")
      .def("summary", no_arguments<RunResult, &simloop::summary_text>("RunResult.summary"),
           "The lines sim_loop prints about the run.")
      .def("write", &write_result<RunResult>, "out"_a,
           "Writes metrics.json and trajectory.csv into out (a directory, made if missing), the bytes sim_loop "
           "writes; returns their paths.")
      .def("__repr__",
           [](const RunResult& r) {
             return "RunResult(seed=" + std::to_string(r.config.seed) + ", steps=" + std::to_string(r.metrics.steps) +
                    ", timestep=" + simloop::python_float_repr(r.timestep) +
                    ", rows=" + std::to_string(r.trajectory.rows()) +
                    ", lateral_drift=" + simloop::python_float_repr(r.metrics.lateral_drift) +
                    ", warnings=" + std::to_string(r.warnings.size()) + ")";
           })
      .def(pickle_as_bytes<RunResult, &simloop::run_result_from_bytes>());
  m.def(
      "run",
      [](const simloop::Model& model, const simloop::RunConfig& config, py::object progress) {
        return long_call(std::move(progress), run_call("run", config), [&](simloop::RunControl* control) {
          simloop::Data workspace(model);
          return simloop::run(model, config, workspace, nullptr, control);
        });
      },
      "model"_a, "config"_a, "progress"_a = py::none());
  m.def(
      "run_batch",
      [](const simloop::Model& model, const std::vector<simloop::RunConfig>& configs, int threads, bool keep_rows,
         py::object progress) {
        const std::string runs = " x " + std::to_string(configs.size()) + " runs";
        const std::string what = !keep_rows        ? "run_batch(metrics_only=True)" + runs
                                 : configs.empty() ? std::string("run_batch")
                                                   : run_call("run_batch", configs.front()) + runs;
        simloop::DiscardRows discard;  // stateless: shared by every run
        const std::vector<simloop::RowSink*> sinks(keep_rows ? 0 : configs.size(), &discard);
        return long_call(std::move(progress), what, [&](simloop::RunControl* control) {
          return simloop::detail::run_chapter_batch(model, configs, sinks, threads, control);
        });
      },
      "model"_a, "configs"_a, "threads"_a, "keep_rows"_a = true, "progress"_a = py::none());

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
      .def_readonly("stable", &simloop::SweepPoint::stable)
      .def("__repr__", [](const simloop::SweepPoint& p) {
        return "SweepPoint(timestep=" + simloop::python_float_repr(p.timestep) + ", steps=" + std::to_string(p.steps) +
               ", stable=" + py_bool(p.stable) +
               ", peak_box_z=" + simloop::python_float_repr(simloop::round6(p.peak_box_z)) +
               ", warnings=" + std::to_string(p.warnings) + ")";
      });
  py::class_<simloop::SweepResult> sweep_result(m, "SweepResult", "A timestep sweep of the baseline run.");
  bind_sweep_outputs<simloop::SweepResult, &simloop::sweep_csv, &simloop::sweep_summary>(
      sweep_result, "The largest stable timestep (None if even the finest is unstable).");
  sweep_result.def_readonly("duration", &simloop::SweepResult::duration)
      .def_readonly("points", &simloop::SweepResult::points)
      .def(pickle_as_bytes<simloop::SweepResult, &simloop::sweep_result_from_bytes>());
  m.def(
      "sweep",
      [](const simloop::Model& model, const std::vector<double>& timesteps, double duration, int threads,
         py::object progress) {
        const std::string what = "sweep(" + std::to_string(timesteps.size()) +
                                 " timesteps, duration=" + simloop::python_float_repr(duration) + ")";
        return long_call(std::move(progress), what, [&](simloop::RunControl* control) {
          return simloop::sweep(model, timesteps, duration, threads, control);
        });
      },
      "model"_a, "timesteps"_a, "duration"_a, "threads"_a, "progress"_a = py::none());
  m.def("log_spaced", &simloop::log_spaced, "start"_a, "stop"_a, "count"_a);
  m.def("default_sweep_timesteps", &simloop::default_sweep_timesteps,
        "The default sweep's 25 round timesteps (1, 2, 3, 4, 5, 6, 8 per decade, 0.0005 s to 1 s).");
  m.attr("BOX_REST_Z") = simloop::kBoxRestZ;

  // A sweep run in chunks on a cluster's workers (python/simloop/distributed.py).
  m.def("join_sweeps", &simloop::join_sweeps, "parts"_a);
  m.def("sweep_steps", &simloop::sweep_steps, "duration"_a, "timestep"_a);
}

}  // namespace simloop_py
