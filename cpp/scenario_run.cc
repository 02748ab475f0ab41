#include "simloop/scenario_run.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <list>
#include <map>
#include <variant>

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
  Scenario effective = scenario;
  if (config.steps) effective.length = When::steps(*config.steps);
  if (!config.perturb) effective.disturbances.clear();
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

double run_timestep(const Model& scene, const Scenario& scenario, const ScenarioConfig& config) {
  return config.timestep.value_or(scenario.timestep.value_or(scene.timestep()));
}

}  // namespace

void check_scenario(const Model& scene, const Scenario& scenario, const ScenarioConfig& config) {
  const Model model = scene.for_run(run_timestep(scene, scenario, config), false);
  const PreparedRun run = prepare(model, scenario, config);
  detail::check_schedule_run(run.schedule.steps, config.record_every);
  (void)Recorder(model.get(), run.resolved, run.schedule);  // its columns' names
}

ScenarioRunResult run_scenario(const Model& scene, const Scenario& scenario, const ScenarioConfig& config,
                               Data* workspace, RowSink* sink, RunControl* control) {
  const Model model = scene.for_run(run_timestep(scene, scenario, config), false);
  std::optional<Data> own;
  if (workspace == nullptr) workspace = &own.emplace(model);
  if (!workspace->fits(model)) throw InvalidArgument("workspace Data was made for a model of another size");
  const PreparedRun run = prepare(model, scenario, config);
  return labelled(
      run_schedule(model.get(), workspace->get(), run.resolved, run.schedule, config.record_every, sink, control),
      model.get(), scenario, config);
}

std::vector<ScenarioRunResult> run_scenario_batch(const Model& scene, const Scenario& scenario,
                                                  const std::vector<ScenarioConfig>& configs, int threads,
                                                  RunControl* control) {
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
                                                                 configs[i].record_every, nullptr, &ctl),
                          m, scenario, configs[i]);
  });
  return results;
}

namespace {

// A JSON value written as Python's json.dumps(value, indent=2,
// sort_keys=True) writes it (ensure_ascii: non-ASCII as \uXXXX escapes).
struct Json {
  using Object = std::map<std::string, Json>;  // sorted keys, as sort_keys=True
  using Array = std::vector<Json>;
  std::variant<bool, std::int64_t, std::uint64_t, double, std::string, Array, Object> value;

  void dump(std::string& out, int indent) const {
    const std::string pad(static_cast<size_t>(indent + 2), ' '), close(static_cast<size_t>(indent), ' ');
    if (const auto* b = std::get_if<bool>(&value)) {
      out += *b ? "true" : "false";
    } else if (const auto* i = std::get_if<std::int64_t>(&value)) {
      out += std::to_string(*i);
    } else if (const auto* u = std::get_if<std::uint64_t>(&value)) {
      out += std::to_string(*u);
    } else if (const auto* x = std::get_if<double>(&value)) {
      out += std::isnan(*x) ? "NaN" : std::isinf(*x) ? (*x > 0 ? "Infinity" : "-Infinity") : python_float_repr(*x);
    } else if (const auto* s = std::get_if<std::string>(&value)) {
      quote(out, *s);
    } else if (const auto* a = std::get_if<Array>(&value)) {
      if (a->empty()) {
        out += "[]";
        return;
      }
      out += "[\n";
      for (size_t k = 0; k < a->size(); ++k) {
        out += pad;
        (*a)[k].dump(out, indent + 2);
        out += k + 1 < a->size() ? ",\n" : "\n";
      }
      out += close + "]";
    } else if (const auto* o = std::get_if<Object>(&value)) {
      if (o->empty()) {
        out += "{}";
        return;
      }
      out += "{\n";
      size_t k = 0;
      for (const auto& [key, item] : *o) {
        out += pad;
        quote(out, key);
        out += ": ";
        item.dump(out, indent + 2);
        out += ++k < o->size() ? ",\n" : "\n";
      }
      out += close + "}";
    }
  }

  static void quote(std::string& out, const std::string& text) {
    out += '"';
    for (size_t i = 0; i < text.size();) {
      const auto c = static_cast<unsigned char>(text[i]);
      char escaped[16];
      if (c == '"' || c == '\\') {
        out += '\\';
        out += static_cast<char>(c);
      } else if (c == '\n') {
        out += "\\n";
      } else if (c == '\r') {
        out += "\\r";
      } else if (c == '\t') {
        out += "\\t";
      } else if (c == '\b') {
        out += "\\b";
      } else if (c == '\f') {
        out += "\\f";
      } else if (c < 0x20 || c == 0x7f) {
        std::snprintf(escaped, sizeof escaped, "\\u%04x", c);
        out += escaped;
      } else if (c < 0x80) {
        out += static_cast<char>(c);
      } else {
        // UTF-8 to code point, then \uXXXX (a surrogate pair above U+FFFF).
        const int length = c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : c >= 0xc0 ? 2 : 1;
        std::uint32_t code = length == 1 ? 0xfffd : c & (0x7f >> length);
        for (int k = 1; k < length; ++k) {
          code = i + static_cast<size_t>(k) < text.size() ? (code << 6) | (static_cast<unsigned char>(text[i + k]) & 0x3f)
                                                           : 0xfffd;
        }
        if (code > 0xffff) {
          code -= 0x10000;
          std::snprintf(escaped, sizeof escaped, "\\u%04x\\u%04x", 0xd800 + (code >> 10), 0xdc00 + (code & 0x3ff));
        } else {
          std::snprintf(escaped, sizeof escaped, "\\u%04x", code);
        }
        out += escaped;
        i += static_cast<size_t>(length);
        continue;
      }
      ++i;
    }
    out += '"';
  }
};

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
