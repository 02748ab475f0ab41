// resolve(): a scenario's names become the model's indices, once, with errors
// that list what the scene has; did_you_mean for likely typos.
#include "simloop/scenario.hpp"
#include "mujoco_compat.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <utility>
#include <string>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/scene_params.hpp"

namespace simloop {

std::string did_you_mean(std::string_view name, const std::vector<std::string>& candidates) {
  // Edit distance with transpositions (optimal string alignment),
  // case-insensitive; a likely typo is at most a third of the longer name's
  // length away ("bodys" for "bodies"), and at least one edit for short names.
  const auto same = [](char a, char b) {
    return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
  };
  std::string best;
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  for (const std::string& candidate : candidates) {
    const std::size_t n = name.size(), k = candidate.size();
    if (std::max(n, k) - std::min(n, k) > std::max<std::size_t>(1, std::max(n, k) / 3)) continue;
    std::vector<std::vector<std::size_t>> dist(n + 1, std::vector<std::size_t>(k + 1));
    for (std::size_t i = 0; i <= n; ++i) dist[i][0] = i;
    for (std::size_t j = 0; j <= k; ++j) dist[0][j] = j;
    for (std::size_t i = 1; i <= n; ++i) {
      for (std::size_t j = 1; j <= k; ++j) {
        dist[i][j] = std::min({dist[i - 1][j] + 1, dist[i][j - 1] + 1,
                               dist[i - 1][j - 1] + (same(name[i - 1], candidate[j - 1]) ? 0 : 1)});
        if (i > 1 && j > 1 && same(name[i - 1], candidate[j - 2]) && same(name[i - 2], candidate[j - 1])) {
          dist[i][j] = std::min(dist[i][j], dist[i - 2][j - 2] + 1);
        }
      }
    }
    if (dist[n][k] <= std::max<std::size_t>(1, std::max(n, k) / 3) && dist[n][k] < best_distance) {
      best_distance = dist[n][k];
      best = candidate;
    }
  }
  return best;
}

namespace {

std::vector<std::string> names_of(const mjModel* m, mjtObj type, int count, bool (*keep)(const mjModel*, int)) {
  std::vector<std::string> out;
  for (int i = 0; i < count; ++i) {
    const char* name = mj_id2name(m, type, i);
    if (name != nullptr && *name != '\0' && (keep == nullptr || keep(m, i))) out.emplace_back(name);
  }
  return out;
}

bool body_moves(const mjModel* m, int body) { return m->body_dofnum[body] > 0; }

std::string join(const std::vector<std::string>& names) {
  if (names.empty()) return "(none)";
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// What a lookup could have named: the names, and the unnamed by index.
std::string listing(const mjModel* m, mjtObj type, int count, bool (*keep)(const mjModel*, int)) {
  std::string unnamed;
  for (int i = 0; i < count; ++i) {
    const char* name = mj_id2name(m, type, i);
    if ((name == nullptr || *name == '\0') && (keep == nullptr || keep(m, i))) {
      unnamed += (unnamed.empty() ? "" : ", ") + std::to_string(i);
    }
  }
  const std::vector<std::string> named = names_of(m, type, count, keep);
  if (unnamed.empty()) return join(named);
  return (named.empty() ? std::string() : join(named) + "; ") + "unnamed, by index: " + unnamed;
}

bool is_index(const std::string& name) {
  return !name.empty() && name.size() <= 9 &&
         std::all_of(name.begin(), name.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// An index past the scene's objects of a kind: what it has, by index and name.
[[noreturn]] void out_of_range(const std::string& context, const char* kind, const std::string& index, int count,
                               const char* what_listed, const std::string& listed) {
  throw InvalidArgument(context + ": " + kind + " index " + index + " is out of range; the scene has " +
                        (count == 0 ? std::string("none") : std::to_string(count) + " (0 to " + std::to_string(count - 1) + ")") +
                        "; " + what_listed + ": " + listed);
}

// A name, or (if no object has that name) an index.
int find(const mjModel* m, mjtObj type, const char* kind, const char* what_listed, int count,
         bool (*listed)(const mjModel*, int), const std::string& name, const std::string& context) {
  const int id = mj_name2id(m, type, name.c_str());
  if (id >= 0) return id;
  if (is_index(name)) {
    const long index = std::stol(name);
    if (index < count) return static_cast<int>(index);
    out_of_range(context, kind, name, count, what_listed, listing(m, type, count, listed));
  }
  const std::vector<std::string> all = names_of(m, type, count, nullptr);
  const std::string hint = did_you_mean(name, all);
  throw InvalidArgument(context + ": no " + kind + " named '" + name + "'" +
                        (hint.empty() ? "" : " (did you mean '" + hint + "'?)") + "; " + what_listed + ": " +
                        listing(m, type, count, listed));
}

int find_actuator(const mjModel* m, const std::string& name, const std::string& context) {
  if (!name.empty() && std::all_of(name.begin(), name.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    const long index = name.size() > 9 ? -1 : std::stol(name);
    const int count = detail::compat::as_int(m->nu);
    if (index < 0 || index >= count) {
      out_of_range(context, "actuator", name, count, "its actuators", listing(m, mjOBJ_ACTUATOR, count, nullptr));
    }
    return static_cast<int>(index);
  }
  return find(m, mjOBJ_ACTUATOR, "actuator", "its actuators", detail::compat::as_int(m->nu), nullptr, name, context);
}

}  // namespace

ResolvedScenario resolve(const Scenario& scenario, const mjModel* m) {
  ResolvedScenario r;
  for (std::size_t i = 0; i < scenario.controls.size(); ++i) {
    const ControlSpec& c = scenario.controls[i];
    const int actuator = find_actuator(m, c.actuator, "control[" + std::to_string(i) + "]");
    for (std::size_t k = 0; k < r.controls.size(); ++k) {
      // Two controls on one actuator: the later would silently win.
      if (r.controls[k].actuator == actuator) {
        throw InvalidArgument("control[" + std::to_string(i) + "]: actuator '" + c.actuator + "' is already driven by control[" +
                              std::to_string(k) + "]; give each actuator one control (a schedule for changes)");
      }
    }
    r.controls.push_back({actuator, c.schedule});
  }
  for (std::size_t i = 0; i < scenario.disturbances.size(); ++i) {
    const DisturbanceSpec& d = scenario.disturbances[i];
    const int body = find(m, mjOBJ_BODY, "body", "bodies that can move", detail::compat::as_int(m->nbody), body_moves, d.body,
                          "disturbance[" + std::to_string(i) + "]");
    if (body == 0) throw InvalidArgument("disturbance[" + std::to_string(i) + "]: the world body cannot be pushed");
    r.disturbances.push_back({body, d});
  }
  const RecordSpec& rec = scenario.record;
  for (const std::string& n : rec.bodies) {
    r.bodies.push_back(find(m, mjOBJ_BODY, "body", "bodies that can move", detail::compat::as_int(m->nbody), body_moves, n, "record.bodies"));
  }
  for (const std::string& n : rec.joints) {
    r.joints.push_back(find(m, mjOBJ_JOINT, "joint", "its joints", detail::compat::as_int(m->njnt), nullptr, n, "record.joints"));
  }
  for (const std::string& n : rec.actuators) r.actuators.push_back(find_actuator(m, n, "record.actuators"));
  for (const std::string& n : rec.sensors) {
    r.sensors.push_back(find(m, mjOBJ_SENSOR, "sensor", "its sensors", detail::compat::as_int(m->nsensor), nullptr, n, "record.sensors"));
  }
  for (const std::string& n : rec.tendons) {
    r.tendons.push_back(find(m, mjOBJ_TENDON, "tendon", "its tendons", detail::compat::as_int(m->ntendon), nullptr, n, "record.tendons"));
  }
  const auto every = [m](std::vector<int>& out, int first, int count, bool keep(const mjModel*, int)) {
    for (int i = first; i < count; ++i) {
      if (keep(m, i) && std::find(out.begin(), out.end(), i) == out.end()) out.push_back(i);
    }
  };
  const auto any = [](const mjModel*, int) { return true; };
  if (rec.all_bodies) every(r.bodies, 1, detail::compat::as_int(m->nbody), body_moves);
  if (rec.all_joints) every(r.joints, 0, detail::compat::as_int(m->njnt), any);
  if (rec.all_actuators) every(r.actuators, 0, detail::compat::as_int(m->nu), any);
  if (rec.all_sensors) every(r.sensors, 0, detail::compat::as_int(m->nsensor), any);
  if (rec.all_tendons) every(r.tendons, 0, detail::compat::as_int(m->ntendon), any);
  // Defaults when nothing is named: every body on a free joint, every actuator.
  if (rec.bodies.empty() && rec.joints.empty() && rec.actuators.empty() && rec.sensors.empty() && rec.tendons.empty() &&
      !rec.all_bodies && !rec.all_joints && !rec.all_actuators && !rec.all_sensors && !rec.all_tendons) {
    for (int b = 1; b < m->nbody; ++b) {
      if (m->body_jntnum[b] >= 1 && m->jnt_type[m->body_jntadr[b]] == mjJNT_FREE) r.bodies.push_back(b);
    }
    for (int a = 0; a < m->nu; ++a) r.actuators.push_back(a);
  }
  r.contacts = rec.contacts;
  r.qpos0.assign(m->qpos0, m->qpos0 + m->nq);
  r.nv = detail::compat::as_int(m->nv);
  check_reset(r, scenario.reset, m);
  return r;
}

void check_reset(const ResolvedScenario& scenario, const ResetSpec& reset, const mjModel* m) {
  const auto check_values = [](const std::string& key, const std::vector<double>& values, std::size_t size,
                               const char* what) {
    if (!values.empty() && values.size() != size) {
      throw InvalidArgument(key + " must hold the scene's " + what + " = " + std::to_string(size) + " values, got " +
                            std::to_string(values.size()));
    }
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (!std::isfinite(values[i])) {
        throw InvalidArgument(key + "[" + std::to_string(i) + "] must be finite, got " + python_float_repr(values[i]));
      }
    }
  };
  check_values("reset.qpos", reset.qpos, scenario.qpos0.size(), "nq");
  check_values("reset.qvel", reset.qvel, static_cast<std::size_t>(scenario.nv), "nv");
  for (const auto& [key, noise] : {std::pair{"reset.qpos_noise", reset.qpos_noise},
                                   std::pair{"reset.qvel_noise", reset.qvel_noise}}) {
    if (!std::isfinite(noise) || noise < 0.0) {
      throw InvalidArgument(std::string(key) + " must be a finite number >= 0, got " + python_float_repr(noise));
    }
  }
  for (std::size_t i = 0; i < reset.params.size(); ++i) {
    const ResetSpec::Param& p = reset.params[i];
    const std::string where = "reset.param[" + std::to_string(i) + "]: ";
    if (!(p.low <= p.high)) {
      throw InvalidArgument(where + "its range must have low <= high, got [" + python_float_repr(p.low) + ", " +
                            python_float_repr(p.high) + "]");
    }
    try {
      check_scene_param(m, {p.kind, p.name, p.low});
      check_scene_param(m, {p.kind, p.name, p.high});
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(where + e.what());
    }
  }
}

}  // namespace simloop
