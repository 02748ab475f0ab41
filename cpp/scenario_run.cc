#include "simloop/scenario_run.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <list>
#include <map>
#include <variant>

#include "json_text.hpp"
#include "run_detail.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/output.hpp"

namespace simloop {

Model load_scene(const Scenario& scenario) {
  if (scenario.scene.empty()) return Model::pusher_scene();
  return Model::from_file(scenario.scene.string());
}

namespace {

// A run of a scenario, made ready on its model: names resolved, inputs
// drawn.
struct PreparedRun {
  ResolvedScenario resolved;
  Schedule schedule;
};

PreparedRun prepare(const Model& model, const Scenario& scenario, const ScenarioConfig& config) {
  const Scenario effective = detail::configured_scenario(scenario, config);
  PreparedRun run;
  run.resolved = resolve(effective, model.get());
  const std::unique_ptr<Draws> draws = make_draws(config.seed, config.rng);
  run.schedule = build_schedule(run.resolved, effective, model.timestep(), *draws);
  return run;
}

ScenarioRunResult labelled(ScenarioRunResult result, const mjModel* m, const Scenario& scenario,
                           const ScenarioConfig& config) {
  result.name = scenario.name;
  result.seed = config.seed;
  result.rng = std::string(rng_name(config.rng));
  result.perturb = config.perturb;
  for (const Schedule::Force& f : result.schedule.forces) {
    const char* name = mj_id2name(m, mjOBJ_BODY, f.body);
    result.disturbed_bodies.push_back(name ? name : "body" + std::to_string(f.body));
  }
  return result;
}

using detail::run_timestep;

}  // namespace

Scenario detail::configured_scenario(const Scenario& scenario, const ScenarioConfig& config) {
  Scenario effective = scenario;
  if (config.steps) effective.length = When::steps(*config.steps);
  if (!config.perturb) effective.disturbances.clear();
  return effective;
}

double detail::run_timestep(const Model& scene, const Scenario& scenario, const ScenarioConfig& config) {
  return config.timestep.value_or(scenario.timestep.value_or(scene.timestep()));
}

void check_scenario(const Model& scene, const Scenario& scenario, const ScenarioConfig& config) {
  const Model model = scene.for_run(run_timestep(scene, scenario, config), false);
  const PreparedRun run = prepare(model, scenario, config);
  detail::check_schedule_run(run.schedule.steps, config.record_every);
  (void)Recorder(model.get(), run.resolved, run.schedule);  // its columns' names
}

ScenarioRunResult run_scenario(const Model& scene, const Scenario& scenario, const ScenarioConfig& config,
                               Data* workspace, RowSink* sink, RunControl* control, Policy* policy) {
  const Model model = scene.for_run(run_timestep(scene, scenario, config), false);
  std::optional<Data> own;
  if (workspace == nullptr) workspace = &own.emplace(model);
  if (!workspace->fits(model)) throw InvalidArgument("workspace Data was made for a model of another size");
  const PreparedRun run = prepare(model, scenario, config);
  return labelled(
      run_schedule(model.get(), workspace->get(), run.resolved, run.schedule, config.record_every, sink, control,
                   policy),
      model.get(), scenario, config);
}

std::vector<ScenarioRunResult> run_scenario_batch(const Model& scene, const Scenario& scenario,
                                                  const std::vector<ScenarioConfig>& configs, int threads,
                                                  RunControl* control, Policy* policy) {
  if (threads < 0) {
    throw InvalidArgument("threads must be at least 1, or 0 for one per core, got " + std::to_string(threads));
  }
  // Up front, on this thread: one model per distinct timestep (the model is
  // frozen while the workers share it), every run's names, inputs and
  // columns, and the memory all the kept rows will take together.
  std::list<std::pair<double, Model>> models;  // stable addresses for model_of
  std::vector<const Model*> model_of;
  std::vector<PreparedRun> runs;
  std::vector<std::array<std::int64_t, 3>> kept;
  for (std::size_t i = 0; i < configs.size(); ++i) {
    const ScenarioConfig& config = configs[i];
    try {
      const double timestep = run_timestep(scene, scenario, config);
      auto it = std::find_if(models.begin(), models.end(), [&](const auto& m) { return m.first == timestep; });
      if (it == models.end()) it = models.emplace(models.end(), timestep, scene.for_run(timestep, false));
      model_of.push_back(&it->second);
      runs.push_back(prepare(it->second, scenario, config));
      detail::check_schedule_run(runs.back().schedule.steps, config.record_every);
      const Recorder columns(it->second.get(), runs.back().resolved, runs.back().schedule);
      kept.push_back({runs.back().schedule.steps, config.record_every, columns.width()});
    } catch (const InvalidArgument& e) {
      throw InvalidArgument("run " + std::to_string(i) + ": " + e.what());
    }
  }
  if (!configs.empty()) detail::check_kept_rows(kept);

  std::vector<ScenarioRunResult> results(configs.size());
  std::vector<std::int64_t> steps;
  for (const PreparedRun& r : runs) steps.push_back(r.schedule.steps);
  detail::run_jobs(scene, configs.size(), threads, steps, control, [&](std::size_t i, Data& data, RunControl& ctl) {
    const mjModel* m = model_of[i]->get();
    results[i] = labelled(detail::run_schedule_counted_elsewhere(m, data.get(), runs[i].resolved, runs[i].schedule,
                                                                 configs[i].record_every, nullptr, &ctl, policy),
                          m, scenario, configs[i]);
  });
  return results;
}

namespace {


using detail::Json;

Json rounded(const double* values, int count) {
  Json::Array a;
  for (int i = 0; i < count; ++i) a.push_back({round6(values[i])});
  return {a};
}


}  // namespace

std::map<std::string, std::size_t> recorded_bodies(const ScenarioRunResult& r) {
  std::map<std::string, std::size_t> out;
  for (size_t c = 0; c + 12 < r.columns.size(); ++c) {
    const std::string& name = r.columns[c].name;
    if (name.size() > 2 && name.compare(name.size() - 2, 2, "_x") == 0 &&
        r.columns[c + 3].name == name.substr(0, name.size() - 2) + "_qw" &&
        r.columns[c + 7].name == name.substr(0, name.size() - 2) + "_vx") {
      out[name.substr(0, name.size() - 2)] = c;
    }
  }
  return out;
}

std::string scenario_metrics_json(const ScenarioRunResult& r) {
  Json::Object m;
  m["scenario"] = {r.name};
  m["seed"] = {r.seed};
  m["rng"] = {r.rng};
  m["perturb"] = {r.perturb};
  m["steps"] = {r.schedule.steps};
  m["timestep"] = {r.timestep};
  Json::Object bodies;
  for (const auto& [name, c] : recorded_bodies(r)) {
    const double* v = r.final_row.data() + c;
    const double speed = std::sqrt(v[7] * v[7] + v[8] * v[8] + v[9] * v[9]);
    bodies[name] = {Json::Object{{"final_pos", rounded(v, 3)}, {"final_speed", {round6(speed)}}}};
  }
  m["bodies"] = {bodies};
  Json::Array disturbances;
  for (size_t i = 0; i < r.schedule.forces.size(); ++i) {
    const Schedule::Force& f = r.schedule.forces[i];
    disturbances.push_back({Json::Object{{"body", {r.disturbed_bodies[i]}},
                                         {"force", rounded(f.wrench.data(), 3)},
                                         {"torque", rounded(f.wrench.data() + 3, 3)},
                                         {"start_step", {f.start}},
                                         {"steps", {f.end - f.start}},
                                         {"steps_asked", {f.asked_end - f.start}}}});
  }
  m["disturbances"] = {disturbances};
  Json::Object warnings;
  for (const Warning& w : r.warnings) warnings[w.name] = {std::int64_t{w.count}};
  m["warnings"] = {warnings};
  std::string out;
  Json{m}.dump(out, 0);
  return out + "\n";
}

std::string scenario_summary(const ScenarioRunResult& r) {
  std::string out;
  char line[512];
  std::snprintf(line, sizeof line, "scenario %s: stepped %lld steps of %s s -> %.2f s of sim time\n",
                r.name.empty() ? "(unnamed)" : r.name.c_str(), static_cast<long long>(r.schedule.steps),
                python_float_repr(r.timestep).c_str(), r.sim_time);
  out += line;
  for (const auto& [name, c] : recorded_bodies(r)) {
    const double* v = r.final_row.data() + c;
    std::snprintf(line, sizeof line, "%s final position [%.3f, %.3f, %.3f], speed %.3f m/s\n", name.c_str(), v[0],
                  v[1], v[2], std::sqrt(v[7] * v[7] + v[8] * v[8] + v[9] * v[9]));
    out += line;
  }
  if (!r.perturb) out += "no disturbances (baseline run)\n";
  for (size_t i = 0; i < r.schedule.forces.size(); ++i) {
    const Schedule::Force& f = r.schedule.forces[i];
    const std::int64_t acted = f.end - f.start, asked = f.asked_end - f.start;
    char window[96];
    if (acted < asked) {
      std::snprintf(window, sizeof window, "%lld step%s from step %lld (of %lld: the run ended first)",
                    static_cast<long long>(acted), acted == 1 ? "" : "s", static_cast<long long>(f.start),
                    static_cast<long long>(asked));
    } else {
      std::snprintf(window, sizeof window, "%lld steps from step %lld", static_cast<long long>(acted),
                    static_cast<long long>(f.start));
    }
    const double* w = f.wrench.data();
    std::snprintf(line, sizeof line, "disturbance on %s: force [%+.2f, %+.2f, %+.2f] N, torque [%+.2f, %+.2f, %+.2f] N m, %s\n",
                  r.disturbed_bodies[i].c_str(), w[0], w[1], w[2], w[3], w[4], w[5], window);
    out += line;
  }
  if (!r.schedule.forces.empty()) {
    std::snprintf(line, sizeof line, "random draws: %s from seed %llu\n", r.rng.c_str(),
                  static_cast<unsigned long long>(r.seed));
    out += line;
  }
  for (const Warning& w : r.warnings) out += warning_line(w);
  return out;
}

OutputFiles write_scenario_outputs(const ScenarioRunResult& r, const std::filesystem::path& dir) {
  const Trajectory& t = r.trajectory;
  if (t.rows() != r.rows) {
    throw InvalidArgument("this result's rows went to a RowSink when it ran; there are none to write");
  }
  OutputWriter writer(dir, r.columns);
  writer.trajectory().start(t.columns(), t.rows());
  writer.trajectory().write(t.data(), t.rows());
  return writer.commit(scenario_metrics_json(r));
}

}  // namespace simloop
