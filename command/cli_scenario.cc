// The command's flags turned into what runs: the quick flags' scenario
// (--body, --ctrl), the checks of a run's inputs in the flags' words, a
// scenario sweep's span and grid, and the ScenarioConfig the flags ask for.
#include <cstdlib>
#include <filesystem>
#include <string>

#include "cli_options.hpp"
#include "simloop/chapter_scene.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/sweep.hpp"

namespace simloop::cli {

Scenario scenario_from_flags(const Options& opts, const Model* scene) {
  Scenario s = Scenario::chapter();
  if (!opts.model_path.empty()) {
    s.scene = opts.model_path;
    s.name = std::filesystem::path(opts.model_path).stem().string();
    s.timestep.reset();  // the scene's own
  }
  if (!opts.ctrls.empty()) {
    s.controls.clear();
    for (const auto& [actuator, value] : opts.ctrls) s.controls.push_back({actuator, {{When::steps(0), value}}, {}});
  } else if (!opts.model_path.empty()) {
    s.controls.clear();
    if (scene != nullptr && scene->get()->nu > 0) s.controls.push_back({"0", {{When::steps(0), 1.0}}, {}});
  }
  if (!opts.body.empty()) {
    s.disturbances[0].body = opts.body;
  } else if (!opts.model_path.empty()) {
    s.disturbances.clear();  // another scene: no shove unless --body names what to shove
  }
  // Record what moves freely, what is pushed (by name, or by index when the
  // scene left it unnamed), and every actuator.
  s.record = RecordSpec{};
  if (scene != nullptr) {
    const mjModel* m = scene->get();
    const std::string pushed = s.disturbances.empty() ? std::string() : s.disturbances[0].body;
    for (int b = 1; b < m->nbody; ++b) {
      const char* name = mj_id2name(m, mjOBJ_BODY, b);
      const std::string id = name != nullptr && *name != '\0' ? std::string(name) : std::to_string(b);
      const bool free = m->body_jntnum[b] >= 1 && m->jnt_type[m->body_jntadr[b]] == mjJNT_FREE;
      if (free || id == pushed || (name != nullptr && *name != '\0' && std::to_string(b) == pushed)) {
        s.record.bodies.push_back(id);
      }
    }
    for (int a = 0; a < m->nu; ++a) s.record.actuators.push_back(std::to_string(a));
  }
  return s;
}

bool nothing_to_push(const Options& opts, const Model& scene) {
  const mjModel* m = scene.get();
  return opts.command == Command::kRun && !opts.model_path.empty() && !opts.is_scenario() && m->nv == 0 && m->nu == 0;
}

namespace {

// A scenario's bad name, in the words of the flags that gave it: the quick
// flags' scenario has the shove as disturbance[0] (--body) and the --ctrl
// values as control[0], control[1]...
std::string scenario_error(const Options& opts, const std::string& what) {
  if (!opts.scenario_path.empty())
    return "--scenario: " + opts.scenario_path + ": " + what;  // as a parse error says it
  const std::string shove = "disturbance[0]: ";
  if (what.rfind(shove, 0) == 0) {
    return "--body" + std::string(opts.body.empty() ? " (default box)" : "") + ": " + what.substr(shove.size());
  }
  if (what.rfind("control[", 0) == 0 && what.find("]: ") != std::string::npos) {
    const size_t index = std::strtoul(what.c_str() + 8, nullptr, 10);
    const size_t rest = what.find("]: ") + 3;
    if (index < opts.ctrls.size()) return "--ctrl " + opts.ctrls[index].first + ": " + what.substr(rest);
    return "actuator 0 (the chapter's ctrl; choose with --ctrl): " + what.substr(rest);
  }
  return what;
}

}  // namespace

void check_run_inputs(Options& opts, const Model& scene, const Scenario* scenario) {
  if (scenario != nullptr) {
    try {
      check_scenario(scene, *scenario, scenario_config(opts));
    } catch (const Error& e) {
      throw UsageError(scenario_error(opts, e.what()));
    }
    if (opts.command == Command::kSweep) complete_scenario_sweep(opts, scene, *scenario);
    return;
  }
  if (const std::string missing = simloop::chapter_layout_missing(scene); !missing.empty()) {
    throw UsageError("--model: " + missing +
                     "; for any other scene, name the body to shove (--body) or run a --scenario");
  }
  if (!opts.model_path.empty() && !opts.timestep_given) opts.run.timestep = scene.timestep();  // the scene's own
}

void complete_scenario_sweep(Options& opts, const Model& scene, const Scenario& scenario) {
  const char* flag = opts.sweep_duration_given ? "--duration" : "--duration (default: the scenario's length)";
  if (!opts.sweep_duration_given) {
    try {
      opts.sweep_duration = scenario_duration(scene, scenario);
    } catch (const Error& e) {
      throw UsageError(scenario_error(opts, e.what()));
    }
  }
  std::string timesteps_flag = std::string(opts.sweep_timesteps.empty() ? "" : "--timesteps/") + flag;
  if (opts.sweep_timesteps.empty()) {
    opts.sweep_timesteps = default_scenario_sweep_timesteps(opts.sweep_duration);
    if (opts.sweep_timesteps.empty()) {
      throw UsageError(std::string(flag) + ": " + python_float_repr(opts.sweep_duration) +
                       " s of sim time is too short for any of the default timesteps (each run needs " +
                       std::to_string(kMinSweepSteps) + " steps); give --duration or --timesteps");
    }
  }
  for (const double dt : opts.sweep_timesteps) {
    try {
      (void)sweep_steps(opts.sweep_duration, dt);
    } catch (const std::exception& e) {
      throw UsageError(timesteps_flag + ": " + e.what());
    }
  }
}

ScenarioConfig scenario_config(const Options& opts) {
  ScenarioConfig c;
  c.seed = opts.run.seed;
  c.rng = opts.run.rng;
  if (opts.timestep_given) c.timestep = opts.run.timestep;
  if (opts.steps_given) c.steps = opts.run.num_steps();
  c.perturb = opts.run.perturb;
  c.record_every = opts.run.record_every;
  c.audit_energy = opts.run.audit_energy;
  return c;
}

}  // namespace simloop::cli
