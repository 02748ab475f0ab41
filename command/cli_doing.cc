// The commands' words for what they were doing when something failed.
#include <string>

#include "cli_options.hpp"
#include "simloop/number_format.hpp"

namespace simloop::cli {

std::string doing(const Options& opts, const Model* scene, const Scenario* scenario) {
  const std::string model = !opts.scenario_path.empty() ? "--scenario " + opts.scenario_path
                            : opts.model_path.empty()   ? "the pusher scene"
                                                        : "--model " + opts.model_path;
  if (opts.command == Command::kSweep) {
    const std::string count = opts.sweep_timesteps.empty() ? "the default timesteps"
                                                           : std::to_string(opts.sweep_timesteps.size()) + " timesteps";
    return "sweeping " + count + " of " + model + " (--duration " + python_float_repr(opts.sweep_duration) +
           ", --threads " + (opts.threads > 0 ? std::to_string(opts.threads) : std::string("auto")) + ")";
  }
  const RunConfig& run = opts.run;
  std::string steps = std::to_string(run.num_steps());
  std::string timestep = "--timestep " + python_float_repr(run.timestep);
  std::string steps_flag = run.smoke ? std::string("--smoke") : "--steps " + steps;
  if (scene != nullptr && scenario != nullptr) {
    const ScenarioConfig config = scenario_config(opts);
    const double dt = run_timestep(*scene, *scenario, config);
    const std::string whose = scenario->timestep ? "the scenario's" : "the scene's own";
    if (!opts.timestep_given) timestep = "timestep " + python_float_repr(dt) + " s: " + whose;
    if (!opts.steps_given) {
      steps = std::to_string(scenario->length.to_steps(dt, 0));
      steps_flag = "the scenario's length";
    }
  }
  return "running " + steps + " steps of " + model + " (" + steps_flag + ", " + timestep + ", --record-every " +
         std::to_string(run.record_every) + ")";
}

}  // namespace simloop::cli
