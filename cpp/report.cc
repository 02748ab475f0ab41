// The texts a run leaves for people and programs: metrics.json (any run's,
// and the chapter's own keys) and the summary lines the commands print.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "json_text.hpp"
#include "simloop/number_format.hpp"
#include "simloop/output.hpp"
#include "simloop/scene_params.hpp"

namespace simloop {

std::string metrics_json(const Metrics& m) {
  using detail::Json;
  Json::Object o;
  Json::Array position;
  for (double x : m.box_final_pos) position.push_back({x});
  o["box_final_pos"] = {position};
  o["box_final_speed"] = {m.box_final_speed};
  o["lateral_drift"] = {m.lateral_drift};
  o["perturb"] = {m.perturb};
  o["pusher_final_x"] = {m.pusher_final_x};
  o["seed"] = {m.seed};
  o["shove_moved_box"] = {m.shove_moved_box};
  o["steps"] = {m.steps};
  std::string out;
  Json{o}.dump(out, 0);
  return out + "\n";
}

std::string warning_line(const Warning& w) {
  std::string line = w.name.rfind("mj", 0) == 0 ? "MuJoCo" : "simloop";
  line += " warning " + w.name + ": raised " + std::to_string(w.count) + (w.count == 1 ? " time" : " times") +
          ", first in step " + std::to_string(w.first_step) + ": " + w.message + "\n";
  return line;
}

namespace {
// The audit's totals in one line, in the run's words for its forces.
std::string energy_line(const EnergyTotals& e, const char* actuators, const char* pushed, const char* passive,
                        const char* contacts) {
  char line[512];
  std::snprintf(line, sizeof line,
                "energy audit: change %+.4f J = work by %s %+.4f, %s %+.4f, %s %+.4f, "
                "%s %+.4f (positive steps %+.4f) + unexplained %+.4f J\n",
                e.energy_end - e.energy_start, actuators, e.work_actuator, pushed, e.work_shove, passive,
                e.work_passive, contacts, e.work_constraint, e.work_constraint_positive, e.unexplained);
  return line;
}
}  // namespace

std::string load_warnings_text(const Model& model) {
  std::string out;
  for (const std::string& w : model.load_warnings()) out += "MuJoCo warning while loading the model: " + w + "\n";
  return out;
}

std::string summary_text(const RunResult& r) {
  const Metrics& m = r.metrics;
  char line[512];
  std::string out;
  std::snprintf(line, sizeof line, "stepped %lld steps of %s s -> %.2f s of sim time\n",
                static_cast<long long>(m.steps), python_float_repr(r.timestep).c_str(), r.sim_time);
  out += line;
  std::snprintf(line, sizeof line, "box final position [%.3f, %.3f, %.3f], speed %.3f m/s\n", m.box_final_pos[0],
                m.box_final_pos[1], m.box_final_pos[2], m.box_final_speed);
  out += line;
  if (m.perturb) {
    // The steps the shove acted: its window, cut short if the run ended in it.
    const std::int64_t pushed = std::max<std::int64_t>(0, std::min(r.shove.num_steps, m.steps - r.shove.start_step));
    char window[64];
    if (pushed < r.shove.num_steps) {
      std::snprintf(window, sizeof window, "%lld step%s (of %lld: the run ended first)", static_cast<long long>(pushed),
                    pushed == 1 ? "" : "s", static_cast<long long>(r.shove.num_steps));
    } else {
      std::snprintf(window, sizeof window, "%lld steps", static_cast<long long>(pushed));
    }
    const std::string_view rng = rng_description(r.shove.rng);
    std::snprintf(line, sizeof line,
                  "shove: %+.1f N in y for %s -> %.3f m of sideways drift (drawn by %.*s from seed %llu)\n",
                  r.shove.force_y(), window, m.lateral_drift, static_cast<int>(rng.size()), rng.data(),
                  static_cast<unsigned long long>(m.seed));
  } else {
    std::snprintf(line, sizeof line, "no shove (baseline run)\n");
  }
  out += line;
  for (const Warning& w : r.warnings) out += warning_line(w);
  if (r.config.audit_energy) out += energy_line(r.energy, "motor", "shove", "damping", "contacts");
  const bool mujoco_warned =
      std::any_of(r.warnings.begin(), r.warnings.end(), [](const Warning& w) { return w.name.rfind("mj", 0) == 0; });
  if (mujoco_warned) {
    out +=
        "  (after a bad-value warning MuJoCo resets the state and carries on: "
        "the numbers above are not one continuous simulation)\n";
  }
  return out;
}

std::string metrics_json(const RunResult& result) { return metrics_json(result.metrics); }

namespace {

using detail::Json;

Json rounded(const double* values, int count) {
  Json::Array a;
  for (int i = 0; i < count; ++i) a.push_back({round6(values[i])});
  return {a};
}

}  // namespace

std::map<std::string, std::size_t> recorded_bodies(const RunRecord& r) { return recorded_bodies(r.columns); }

bool audited(const RunRecord& r) {
  return std::any_of(r.columns.begin(), r.columns.end(),
                     [](const Column& c) { return c.name == "energy_unexplained"; });
}

std::map<std::string, std::size_t> recorded_bodies(const std::vector<Column>& columns) {
  std::map<std::string, std::size_t> out;
  for (size_t c = 0; c < columns.size(); ++c) {
    if (!columns[c].body.empty()) out.emplace(columns[c].body, c);  // the first of its columns
  }
  return out;
}

std::string metrics_json(const RunRecord& r) {
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
  // The scene parameters this run drew at its reset ([[reset.param]]): what
  // a sweep of domain randomisation is read by. Absent when none are drawn.
  if (!r.schedule.start.params.empty()) {
    Json::Array params;
    for (const SceneParam& p : r.schedule.start.params) {
      Json::Object param{
          {"kind", {std::string(scene_param_kind_name(p.kind))}}, {"name", {p.name}}, {"value", {round6(p.value)}}};
      if (p.kind == SceneParam::Kind::kModel) {
        param["field"] = {p.field};
        param["index"] = {std::int64_t{p.index}};
      }
      params.push_back({param});
    }
    m["params"] = {params};
  }
  Json::Object warnings;
  for (const Warning& w : r.warnings) warnings[w.name] = {std::int64_t{w.count}};
  m["warnings"] = {warnings};
  std::string out;
  Json{m}.dump(out, 0);
  return out + "\n";
}

std::string summary_text(const RunRecord& r) {
  std::string out;
  char line[512];
  std::snprintf(line, sizeof line, "scenario %s: stepped %lld steps of %s s -> %.2f s of sim time\n",
                r.name.empty() ? "(unnamed)" : r.name.c_str(), static_cast<long long>(r.schedule.steps),
                python_float_repr(r.timestep).c_str(), r.sim_time);
  out += line;
  for (const auto& [name, c] : recorded_bodies(r)) {
    const double* v = r.final_row.data() + c;
    std::snprintf(line, sizeof line, "%s final position [%.3f, %.3f, %.3f], speed %.3f m/s\n", name.c_str(), v[0], v[1],
                  v[2], std::sqrt(v[7] * v[7] + v[8] * v[8] + v[9] * v[9]));
    out += line;
  }
  if (!r.perturb) out += "no disturbances (baseline run)\n";
  for (size_t i = 0; i < r.schedule.forces.size(); ++i) {
    const Schedule::Force& f = r.schedule.forces[i];
    const std::int64_t acted = f.end - f.start, asked = f.asked_end - f.start;
    char window[96];
    if (acted == 0 && f.start >= r.schedule.steps) {  // its start is past the run's end (start is clamped to it)
      std::snprintf(window, sizeof window, "never: it starts after the run's %lld steps",
                    static_cast<long long>(r.schedule.steps));
    } else if (acted < asked) {
      std::snprintf(window, sizeof window, "%lld step%s from step %lld (of %lld: the run ended first)",
                    static_cast<long long>(acted), acted == 1 ? "" : "s", static_cast<long long>(f.start),
                    static_cast<long long>(asked));
    } else {
      std::snprintf(window, sizeof window, "%lld step%s from step %lld", static_cast<long long>(acted),
                    acted == 1 ? "" : "s", static_cast<long long>(f.start));
    }
    const double* w = f.wrench.data();
    std::snprintf(line, sizeof line,
                  "disturbance on %s: force [%+.2f, %+.2f, %+.2f] N, torque [%+.2f, %+.2f, %+.2f] N m, %s\n",
                  r.disturbed_bodies[i].c_str(), w[0], w[1], w[2], w[3], w[4], w[5], window);
    out += line;
  }
  if (!r.schedule.start.params.empty()) {
    std::string drawn;
    for (const SceneParam& p : r.schedule.start.params) {
      char value[32];
      std::snprintf(value, sizeof value, "%.4g", p.value);
      const bool model = p.kind == SceneParam::Kind::kModel;
      const char* every = p.kind == SceneParam::Kind::kFriction  ? " of every geom"
                          : p.kind == SceneParam::Kind::kDamping ? " of every joint"
                          : model                                ? " of every row"
                                                                 : "";
      const std::string what =
          model ? p.field + "[" + std::to_string(p.index) + "]" : std::string(scene_param_kind_name(p.kind));
      drawn += (drawn.empty() ? "" : ", ") + what + (p.name.empty() ? every : " of '" + p.name + "'") + " = " + value;
    }
    out += "scene parameters drawn: " + drawn + "\n";
  }
  if (!r.schedule.forces.empty() || !r.schedule.start.params.empty()) {
    std::snprintf(line, sizeof line, "random draws: %s from seed %llu\n", r.rng.c_str(),
                  static_cast<unsigned long long>(r.seed));
    out += line;
  }
  for (const Warning& w : r.warnings) out += warning_line(w);
  const bool audited =
      std::any_of(r.columns.begin(), r.columns.end(), [](const Column& c) { return c.name == "energy_unexplained"; });
  if (audited) out += energy_line(r.energy, "actuators", "disturbances", "passive forces", "constraints");
  return out;
}

}  // namespace simloop
