// resolve(): a scenario's names become the model's indices, once, with errors
// that list what the scene has; did_you_mean for likely typos.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "mujoco_compat.hpp"
#include "simloop/errors.hpp"
#include "simloop/fields.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scene_params.hpp"

namespace simloop {

namespace {

constexpr ObjectFilter kMovingBodies{"bodies that can move", body_can_move};
constexpr ObjectFilter kPushableBodies{"bodies a force can move", body_can_be_pushed};

// A name, or (if no object has that name) an index; `context` leads the
// error, which lists the objects `listed` passes.
int find(const mjModel* m, mjtObj type, const std::string& name, const std::string& context, ObjectFilter listed = {}) {
  try {
    return object_id_or_index(m, type, name, listed);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(context + ": " + e.what());
  }
}

// mjData's arrays a run writes or steps (the state and the inputs), which
// record.data refuses: joints, actuators and disturbances record them.
bool state_or_input(std::string_view array) {
  for (const char* name : {"qpos", "qvel", "act", "qacc_warmstart", "ctrl", "qfrc_applied", "xfrc_applied", "mocap_pos",
                           "mocap_quat", "userdata", "plugin_state"}) {
    if (array == name) return true;
  }
  return false;
}

// record.data's [array, object]: the values of the object's row.
ResolvedScenario::DataValues data_values(const mjModel* m, const std::string& array, const std::string& object,
                                         const std::string& context) {
  static const mjData no_data{};  // the arrays' shapes are the model's: nothing of a run's is read
  FieldView f;
  try {
    f = data_field(m, &no_data, array);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(context + ": " + e.what());
  }
  if (state_or_input(array)) {
    throw InvalidArgument(context + ": mjData's " + array +
                          " is the state or an input: record joints, actuators or disturbances instead");
  }
  if (f.element != Element::kFloat64) throw InvalidArgument(context + ": mjData's " + array + " is not numbers");
  ResolvedScenario::DataValues v{array, f.rows_are, -1, 0, static_cast<int>(f.cols)};
  if (f.rows_are != mjOBJ_UNKNOWN) {
    v.id = find(m, f.rows_are, object, context);
    v.first = v.id * f.cols;
  } else if (f.rows_count == "nq" || f.rows_count == "nv") {
    v.type = mjOBJ_JOINT;
    v.id = find(m, mjOBJ_JOINT, object, context);
    const JointSize size = joint_size(m->jnt_type[v.id]);
    v.first = f.rows_count == "nq" ? m->jnt_qposadr[v.id] : m->jnt_dofadr[v.id];
    v.count = f.rows_count == "nq" ? size.nq : size.nv;
  } else if (f.rows_count == "nsensordata") {
    v.type = mjOBJ_SENSOR;
    v.id = find(m, mjOBJ_SENSOR, object, context);
    v.first = m->sensor_adr[v.id];
    v.count = m->sensor_dim[v.id];
  } else {
    throw InvalidArgument(context + ": mjData's " + array + "'s rows are not objects (its rows: " + f.rows_count +
                          "); record arrays with a row per body, geom, site, joint, sensor, ...");
  }
  return v;
}

// record.contact_forces' side: a geom of that name, else a body (all its
// geoms); a name neither has is refused naming both kinds.
void contact_side(const mjModel* m, const std::string& name, const std::string& context, mjtObj& type, int& id) {
  id = named_object_id(m, mjOBJ_GEOM, name);
  type = id >= 0 ? mjOBJ_GEOM : mjOBJ_BODY;
  if (id >= 0) return;
  if (is_index_text(name) || named_object_id(m, mjOBJ_BODY, name) >= 0) {
    id = find(m, mjOBJ_BODY, name, context);
    return;
  }
  std::vector<std::string> names = object_names(m, mjOBJ_GEOM);
  for (std::string& body : object_names(m, mjOBJ_BODY)) names.push_back(std::move(body));
  const std::string hint = did_you_mean(name, names);
  throw InvalidArgument(context + ": no geom or body named '" + name + "'" +
                        (hint.empty() ? "" : " (did you mean '" + hint + "'?)") + "; " + object_listing(m, mjOBJ_GEOM) +
                        "; " + object_listing(m, mjOBJ_BODY));
}

}  // namespace

void ResolvedScenario::ContactPair::force(const mjModel* m, const mjData* d, double out[3]) const noexcept {
  const auto is = [m](mjtObj type, int id, int geom) {
    return geom >= 0 && geom < m->ngeom && (type == mjOBJ_GEOM ? geom == id : m->geom_bodyid[geom] == id);
  };
  std::fill_n(out, 3, 0.0);
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    const double sign = is(type_a, a, c.geom1) && is(type_b, b, c.geom2)   ? 1.0
                        : is(type_b, b, c.geom1) && is(type_a, a, c.geom2) ? -1.0
                                                                           : 0.0;
    if (sign == 0.0) continue;
    mjtNum f[6];
    mj_contactForce(m, d, i, f);
    for (int k = 0; k < 3; ++k) out[k] += sign * (c.frame[k] * f[0] + c.frame[3 + k] * f[1] + c.frame[6 + k] * f[2]);
  }
}

ResolvedScenario resolve(const Scenario& scenario, const mjModel* m) {
  ResolvedScenario r;
  for (std::size_t i = 0; i < scenario.controls.size(); ++i) {
    const ControlSpec& c = scenario.controls[i];
    const int actuator = find(m, mjOBJ_ACTUATOR, c.actuator, "control[" + std::to_string(i) + "]");
    for (std::size_t k = 0; k < r.controls.size(); ++k) {
      // Two controls on one actuator: the later would silently win.
      if (r.controls[k].actuator == actuator) {
        throw InvalidArgument("control[" + std::to_string(i) + "]: actuator '" + c.actuator +
                              "' is already driven by control[" + std::to_string(k) +
                              "]; give each actuator one control (a schedule for changes)");
      }
    }
    r.controls.push_back({actuator, c.schedule});
  }
  for (std::size_t i = 0; i < scenario.disturbances.size(); ++i) {
    const DisturbanceSpec& d = scenario.disturbances[i];
    const std::string where = "disturbance[" + std::to_string(i) + "]";
    const int body = find(m, mjOBJ_BODY, d.body, where, kPushableBodies);
    if (body == 0) throw InvalidArgument(where + ": the world body cannot be pushed");
    if (!body_can_be_pushed(m, body)) {
      throw InvalidArgument(
          where + ": a force on body '" + d.body + "' moves nothing: it is " +
          (body_can_move(m, body) ? "a mocap body or fixed to one (moved by mocap_pos)" : "fixed to the world") + "; " +
          object_listing(m, mjOBJ_BODY, kPushableBodies));
    }
    r.disturbances.push_back({body, d});
  }
  const RecordSpec& rec = scenario.record;
  for (const std::string& n : rec.bodies) {
    r.bodies.push_back(find(m, mjOBJ_BODY, n, "record.bodies", kMovingBodies));
  }
  for (const std::string& n : rec.joints) {
    r.joints.push_back(find(m, mjOBJ_JOINT, n, "record.joints"));
  }
  for (const std::string& n : rec.actuators) r.actuators.push_back(find(m, mjOBJ_ACTUATOR, n, "record.actuators"));
  for (const std::string& n : rec.sensors) {
    r.sensors.push_back(find(m, mjOBJ_SENSOR, n, "record.sensors"));
  }
  for (const std::string& n : rec.tendons) {
    r.tendons.push_back(find(m, mjOBJ_TENDON, n, "record.tendons"));
  }
  for (std::size_t i = 0; i < rec.data.size(); ++i) {
    const auto& [array, object] = rec.data[i];
    r.data.push_back(data_values(m, array, object, "record.data[" + std::to_string(i) + "]"));
  }
  for (std::size_t i = 0; i < rec.contact_forces.size(); ++i) {
    const auto& [a, b] = rec.contact_forces[i];
    ResolvedScenario::ContactPair& p = r.contact_pairs.emplace_back();
    const std::string context = "record.contact_forces[" + std::to_string(i) + "]";
    contact_side(m, a, context, p.type_a, p.a);
    contact_side(m, b, context, p.type_b, p.b);
    p.name = a + "_" + b;
  }
  const auto every = [m](std::vector<int>& out, int first, int count, bool keep(const mjModel*, int)) {
    for (int i = first; i < count; ++i) {
      if (keep(m, i) && std::find(out.begin(), out.end(), i) == out.end()) out.push_back(i);
    }
  };
  const auto any = [](const mjModel*, int) { return true; };
  if (rec.all_bodies) every(r.bodies, 1, detail::compat::as_int(m->nbody), body_can_move);
  if (rec.all_joints) every(r.joints, 0, detail::compat::as_int(m->njnt), any);
  if (rec.all_actuators) every(r.actuators, 0, detail::compat::as_int(m->nu), any);
  if (rec.all_sensors) every(r.sensors, 0, detail::compat::as_int(m->nsensor), any);
  if (rec.all_tendons) every(r.tendons, 0, detail::compat::as_int(m->ntendon), any);
  // Defaults when nothing is named: every body on a free joint, every actuator.
  if (rec.bodies.empty() && rec.joints.empty() && rec.actuators.empty() && rec.sensors.empty() && rec.tendons.empty() &&
      rec.data.empty() && rec.contact_forces.empty() && !rec.all_bodies && !rec.all_joints && !rec.all_actuators &&
      !rec.all_sensors && !rec.all_tendons) {
    for (int b = 1; b < m->nbody; ++b) {
      if (m->body_jntnum[b] >= 1 && m->jnt_type[m->body_jntadr[b]] == mjJNT_FREE) r.bodies.push_back(b);
    }
    for (int a = 0; a < m->nu; ++a) r.actuators.push_back(a);
  }
  r.contacts = rec.contacts;
  r.ncon = rec.ncon;
  r.qpos0.assign(m->qpos0, m->qpos0 + m->nq);
  r.nv = detail::compat::as_int(m->nv);
  const std::vector<std::string> joint_names = object_names(m, mjOBJ_JOINT);
  for (int j = 0; j < m->njnt; ++j) {
    const JointSize size = joint_size(m->jnt_type[j]);
    r.joint_coordinates.push_back(
        {joint_names[static_cast<std::size_t>(j)], m->jnt_qposadr[j], size.nq, m->jnt_dofadr[j], size.nv});
  }
  r.keyframes = object_names(m, mjOBJ_KEY);
  r.key_qpos.assign(m->key_qpos, m->key_qpos + static_cast<std::ptrdiff_t>(m->nkey) * m->nq);
  r.key_qvel.assign(m->key_qvel, m->key_qvel + static_cast<std::ptrdiff_t>(m->nkey) * m->nv);
  const std::vector<std::string> body_names = object_names(m, mjOBJ_BODY);
  for (int b = 0; b < m->nbody; ++b) {
    if (m->body_mocapid[b] >= 0)
      r.mocap_bodies.emplace_back(body_names[static_cast<std::size_t>(b)], m->body_mocapid[b]);
  }
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
  for (const auto& [key, noise, of_qpos] : {std::tuple{"reset.qpos_noise", &reset.qpos_noise, true},
                                            std::tuple{"reset.qvel_noise", &reset.qvel_noise, false}}) {
    const std::size_t size = of_qpos ? scenario.qpos0.size() : static_cast<std::size_t>(scenario.nv);
    if (!noise->each.empty() && noise->each.size() != size) {
      throw InvalidArgument(std::string(key) + " must hold the scene's " + (of_qpos ? "nq" : "nv") + " = " +
                            std::to_string(size) + " widths (one per coordinate), got " +
                            std::to_string(noise->each.size()));
    }
    for (const auto& [joint, width] : noise->joints) {
      try {
        (void)object_id(m, mjOBJ_JOINT, joint);
      } catch (const InvalidArgument& e) {
        throw InvalidArgument(std::string(key) + ": " + e.what());
      }
    }
    for (const double w : noise_widths(scenario, *noise, of_qpos)) {
      if (!std::isfinite(2.0 * w) || w < 0.0) {
        throw InvalidArgument(std::string(key) + " must be finite numbers >= 0, got " + python_float_repr(w));
      }
    }
  }
  if (!reset.keyframe.empty()) {
    try {
      (void)object_id(m, mjOBJ_KEY, reset.keyframe);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(std::string("reset.keyframe: ") + e.what());
    }
  }
  for (std::size_t i = 0; i < reset.goals.size(); ++i) {
    const std::string where = "reset.goal[" + std::to_string(i) + "].body: ";
    int body = -1;
    try {
      body = object_id(m, mjOBJ_BODY, reset.goals[i].body);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(where + e.what());
    }
    if (m->body_mocapid[body] < 0) {
      std::string mocap;
      for (const auto& [name, id] : scenario.mocap_bodies) mocap += (mocap.empty() ? "" : ", ") + name;
      throw InvalidArgument(where + "'" + reset.goals[i].body +
                            "' is not a mocap body; the scene's mocap bodies: " + (mocap.empty() ? "none" : mocap));
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
      check_scene_param(m, {p.kind, p.name, p.low, p.field, p.index});
      check_scene_param(m, {p.kind, p.name, p.high, p.field, p.index});
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(where + e.what());
    }
  }
}

std::vector<double> noise_widths(const ResolvedScenario& scenario, const ResetSpec::Noise& noise, bool of_qpos) {
  const std::size_t size = of_qpos ? scenario.qpos0.size() : static_cast<std::size_t>(scenario.nv);
  if (!noise.each.empty()) return noise.each;
  std::vector<double> widths(size, noise.joints.empty() ? noise.scale : 0.0);
  for (const auto& [joint, width] : noise.joints) {
    for (const ResolvedScenario::JointCoordinates& c : scenario.joint_coordinates) {
      if (c.name != joint) continue;
      const int first = of_qpos ? c.qpos_first : c.dof_first, count = of_qpos ? c.qpos_count : c.dof_count;
      std::fill_n(widths.begin() + first, count, width);
      break;
    }
  }
  return widths;
}

}  // namespace simloop
