#include "simloop/recorder.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "energy_audit.hpp"
#include "loop.hpp"
#include "mujoco_compat.hpp"
#include "run_detail.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"
#include "simloop/state.hpp"

namespace simloop {
namespace {

constexpr double kNone = std::numeric_limits<double>::quiet_NaN();

std::vector<std::string> suffixed(const std::string& base, std::initializer_list<const char*> suffixes) {
  std::vector<std::string> out;
  for (const char* s : suffixes) out.push_back(base + s);
  return out;
}

// base_<suffix>, or base_<suffix>0, base_<suffix>1... for several numbers.
std::vector<std::string> numbered(const std::string& base, const char* suffix, int count) {
  if (count == 1) return {base + suffix};
  std::vector<std::string> out;
  for (int i = 0; i < count; ++i) out.push_back(base + suffix + std::to_string(i));
  return out;
}

// A joint's columns' units: a free joint's position is metres then a
// quaternion (no unit), its velocity m/s then rad/s; a ball's a quaternion
// and rad/s.
std::vector<std::string> joint_units(int type, bool velocity) {
  if (type == mjJNT_SLIDE) return {velocity ? "m/s" : "m"};
  if (type == mjJNT_HINGE) return {velocity ? "rad/s" : "rad"};
  if (type == mjJNT_BALL) return velocity ? std::vector<std::string>(3, "rad/s") : std::vector<std::string>(4, "");
  return velocity ? std::vector<std::string>{"m/s", "m/s", "m/s", "rad/s", "rad/s", "rad/s"}
                  : std::vector<std::string>{"m", "m", "m", "", "", "", ""};
}

// mjData's arrays that an observation's first half of a step (mj_step1 and
// mj_fwdActuation: Stepper::observe) derives; a recorded array not among
// them makes observations take a whole forward pass.
bool derived_before_acceleration(std::string_view array) {
  for (const char* name :
       {"xpos",           "xquat",         "xmat",       "xipos",        "ximat",           "xanchor",
        "xaxis",          "geom_xpos",     "geom_xmat",  "site_xpos",    "site_xmat",       "cam_xpos",
        "cam_xmat",       "light_xpos",    "light_xdir", "subtree_com",  "cinert",          "cdof",
        "cvel",           "cdof_dot",      "ten_length", "ten_velocity", "actuator_length", "actuator_velocity",
        "actuator_force", "qfrc_actuator", "qfrc_bias",  "qfrc_passive"}) {
    if (array == name) return true;
  }
  return false;
}

}  // namespace

std::vector<std::string> joint_position_columns(const mjModel* m, int joint) {
  return numbered(object_name(m, mjOBJ_JOINT, joint), "_pos", joint_size(m->jnt_type[joint]).nq);
}

CtrlRange ctrl_range(const mjModel* m) {
  CtrlRange r{std::vector<double>(static_cast<size_t>(m->nu), -std::numeric_limits<double>::infinity()),
              std::vector<double>(static_cast<size_t>(m->nu), std::numeric_limits<double>::infinity())};
  for (int a = 0; a < m->nu; ++a) {
    if (m->actuator_ctrllimited[a] && !(m->opt.disableflags & mjDSBL_CLAMPCTRL)) {
      r.low[static_cast<size_t>(a)] = m->actuator_ctrlrange[2 * a];
      r.high[static_cast<size_t>(a)] = m->actuator_ctrlrange[2 * a + 1];
    }
  }
  return r;
}

void Recorder::add(Source::Kind kind, int id, int count, const std::vector<std::string>& names,
                   const std::vector<std::string>& units, bool integer, bool input, const std::string& body) {
  Source source{kind, id, count, width()};
  for (std::size_t i = 0; i < names.size(); ++i) {
    columns_.push_back({names[i], units.size() == 1 ? units[0] : units.at(i), integer, input, body});
  }
  // (kNcon is read before the step: it is the count the step begins with.)
  const bool derived = kind == Source::kBodyPose || kind == Source::kBodyVelocity || kind == Source::kActuatorForce ||
                       kind == Source::kSensor || kind == Source::kTendon || kind == Source::kData ||
                       kind == Source::kContactForce || kind == Source::kContacts;
  (derived ? after_ : before_).push_back(source);
}

Recorder::Recorder(const mjModel* m, const ResolvedScenario& scenario, const Schedule& schedule, bool energy) {
  columns_.push_back({"step", "", true, false, ""});
  columns_.push_back({"time", "s", false, false, ""});
  ctrl_range_ = ctrl_range(m);
  // Inputs: the ctrl of every controlled or recorded actuator, the force on
  // every disturbed body.
  std::set<int> ctrl_of;
  for (const auto& c : scenario.controls) ctrl_of.insert(c.actuator);
  ctrl_of.insert(scenario.actuators.begin(), scenario.actuators.end());
  for (int a : ctrl_of) {
    add(Source::kCtrl, a, 1, {object_name(m, mjOBJ_ACTUATOR, a) + "_ctrl"}, {""}, false, true);
  }
  std::set<int> pushed;
  for (const Schedule::Force& f : schedule.forces) pushed.insert(f.body);
  for (int b : pushed) {
    add(Source::kXfrc, b, 6, suffixed(object_name(m, mjOBJ_BODY, b), {"_fx", "_fy", "_fz", "_tx", "_ty", "_tz"}),
        {"N", "N", "N", "N m", "N m", "N m"}, false, true);
  }
  for (int b : scenario.bodies) {
    const std::string base = object_name(m, mjOBJ_BODY, b);
    const std::vector<std::string> pose = suffixed(base, {"_x", "_y", "_z", "_qw", "_qx", "_qy", "_qz"});
    const std::vector<std::string> velocity = suffixed(base, {"_vx", "_vy", "_vz", "_wx", "_wy", "_wz"});
    // A free joint of the world holds exactly these numbers, as the chapter
    // reads its box: the quaternion as integrated (xquat is it normalised
    // again), the linear velocity in the world frame, the angular in the
    // body's. (A free joint deeper in the tree moves relative to its parent.)
    const int joint = m->body_jntadr[b];
    if (m->body_jntnum[b] >= 1 && m->jnt_type[joint] == mjJNT_FREE && m->body_parentid[b] == 0) {
      add(Source::kQpos, m->jnt_qposadr[joint], 7, pose, joint_units(mjJNT_FREE, false), false, false, base);
      add(Source::kQvel, m->jnt_dofadr[joint], 6, velocity, joint_units(mjJNT_FREE, true), false, false, base);
    } else {
      add(Source::kBodyPose, b, 7, pose, joint_units(mjJNT_FREE, false), false, false, base);
      add(Source::kBodyVelocity, b, 6, velocity, joint_units(mjJNT_FREE, true), false, false, base);
    }
  }
  for (int j : scenario.joints) {
    const std::string base = object_name(m, mjOBJ_JOINT, j);
    const int type = m->jnt_type[j];
    const auto [nq, nv] = joint_size(type);
    add(Source::kQpos, m->jnt_qposadr[j], nq, joint_position_columns(m, j), joint_units(type, false));
    add(Source::kQvel, m->jnt_dofadr[j], nv, numbered(base, "_vel", nv), joint_units(type, true));
  }
  for (int a : scenario.actuators) {
    add(Source::kActuatorForce, a, 1, {object_name(m, mjOBJ_ACTUATOR, a) + "_force"}, {"N or N m"});
  }
  for (int s : scenario.sensors) {
    add(Source::kSensor, m->sensor_adr[s], m->sensor_dim[s],
        numbered(object_name(m, mjOBJ_SENSOR, s), "", m->sensor_dim[s]), {""});
    reads_acceleration_stage_ = reads_acceleration_stage_ || m->sensor_needstage[s] == mjSTAGE_ACC;
  }
  for (int t : scenario.tendons) {  // a spatial tendon's metres, a fixed one's sum of its joints' coordinates
    const bool spatial = m->wrap_type[m->tendon_adr[t]] != mjWRAP_JOINT;
    add(Source::kTendon, t, 2, suffixed(object_name(m, mjOBJ_TENDON, t), {"_length", "_vel"}),
        spatial ? std::vector<std::string>{"m", "m/s"} : std::vector<std::string>{"m or rad", "m/s or rad/s"});
  }
  for (const ResolvedScenario::DataValues& v : scenario.data) {
    add(Source::kData, static_cast<int>(data_.size()), v.count,
        numbered(object_name(m, v.type, v.id) + "_", v.array.c_str(), v.count), {""});
    data_.emplace_back(data_numbers(v.array), v.first);
    const bool same_fill = std::any_of(fills_.begin(), fills_.end(), [&](const std::string& f) {
      return filled_after_constraint(f) == filled_after_constraint(v.array);
    });
    if (filled_on_request(v.array) && !same_fill) fills_.push_back(v.array);
    reads_acceleration_stage_ = reads_acceleration_stage_ || !derived_before_acceleration(v.array);
  }
  for (const ResolvedScenario::ContactPair& p : scenario.contact_pairs) {  // (from efc_force: a whole forward pass)
    add(Source::kContactForce, static_cast<int>(contact_pairs_.size()), 3, numbered(p.name, "_contact_force", 3),
        {"N"});
    contact_pairs_.push_back(p);
    reads_acceleration_stage_ = true;
  }
  if (scenario.contacts) add(Source::kContacts, 0, 1, {"contacts"}, {""}, true);
  if (scenario.ncon) add(Source::kNcon, 0, 1, {"ncon"}, {""}, true);
  if (energy) {  // no Source: the energy audit (energy_audit.hpp) fills them
    energy_column_ = width();
    for (const char* name : {"energy", "work_actuator", "work_shove", "work_passive", "work_constraint",
                             "work_constraint_positive", "energy_unexplained"}) {
      columns_.push_back({name, "J", false, false, ""});
    }
  }

  std::set<std::string> seen;
  for (const Column& c : columns_) {
    if (!seen.insert(c.name).second) {
      throw InvalidArgument("two recorded columns would both be named '" + c.name +
                            "': rename one of the scene's elements, or record fewer");
    }
  }
}

void Recorder::before_step(double* row, std::int64_t step, const mjModel* m, const mjData* d, bool inputs,
                           int ncon) const noexcept {
  (void)m;
  row[0] = static_cast<double>(step);
  row[1] = d->time;
  for (const Source& s : before_) {
    double* out = row + s.column;
    switch (s.kind) {
      case Source::kCtrl:
        // What MuJoCo applies: ctrl clamped to ctrlrange (it clamps a copy).
        out[0] = inputs ? std::clamp(d->ctrl[s.id], ctrl_range_.low[static_cast<size_t>(s.id)],
                                     ctrl_range_.high[static_cast<size_t>(s.id)])
                        : kNone;
        break;
      case Source::kXfrc:
        for (int i = 0; i < 6; ++i) out[i] = inputs ? d->xfrc_applied[6 * s.id + i] : kNone;
        break;
      case Source::kQpos:
        std::copy(d->qpos + s.id, d->qpos + s.id + s.count, out);
        break;
      case Source::kQvel:
        std::copy(d->qvel + s.id, d->qvel + s.id + s.count, out);
        break;
      case Source::kNcon:
        out[0] = ncon;
        break;
      default:
        break;
    }
  }
}

void Recorder::after_step(double* row, const mjModel* m, mjData* d) const noexcept {
  // (Inside MuJoCo's error guard, as every call of the loop's.)
  if (!data_at_step_) {
    for (const std::string& array : fills_) fill_derived(m, d, array);
  }
  for (const Source& s : after_) {
    double* out = row + s.column;
    switch (s.kind) {
      case Source::kBodyPose:
        std::copy(d->xpos + 3 * s.id, d->xpos + 3 * s.id + 3, out);
        std::copy(d->xquat + 4 * s.id, d->xquat + 4 * s.id + 4, out + 3);
        break;
      case Source::kBodyVelocity: {
        // MuJoCo's order: angular, then linear; the linear in the world
        // frame, the angular in the body's, as a free joint's qvel holds them.
        mjtNum world[6], local[6];
        mj_objectVelocity(m, d, mjOBJ_XBODY, s.id, world, 0);
        mj_objectVelocity(m, d, mjOBJ_XBODY, s.id, local, 1);
        std::copy(world + 3, world + 6, out);
        std::copy(local, local + 3, out + 3);
        break;
      }
      case Source::kActuatorForce:
        out[0] = d->actuator_force[s.id];
        break;
      case Source::kSensor:
        std::copy(d->sensordata + s.id, d->sensordata + s.id + s.count, out);
        break;
      case Source::kTendon:
        out[0] = d->ten_length[s.id];
        out[1] = d->ten_velocity[s.id];
        break;
      case Source::kData: {
        if (data_at_step_) break;  // (read_data's)
        const auto& [array, first] = data_[static_cast<std::size_t>(s.id)];
        std::copy_n(d->*array + first, s.count, out);
        break;
      }
      case Source::kContactForce:
        contact_pairs_[static_cast<std::size_t>(s.id)].force(m, d, out);
        break;
      case Source::kContacts:
        out[0] = d->ncon;
        break;
      default:
        break;
    }
  }
}

void Recorder::read_data(double* row, const mjModel* m, mjData* d, bool stepped) const noexcept {
  if (stepped) {  // (what a step does not fill, as Gymnasium's MujocoEnv fills it)
    for (const std::string& array : fills_) {
      if (filled_after_constraint(array)) fill_derived(m, d, array);
    }
  }
  for (const Source& s : after_) {
    if (s.kind != Source::kData) continue;
    const auto& [array, first] = data_[static_cast<std::size_t>(s.id)];
    std::copy_n(d->*array + first, s.count, row + s.column);
  }
}

ScheduledInputs::ScheduledInputs(const Schedule& schedule, bool controls) {
  if (controls) controls_ = schedule.control_changes;
  // What xfrc_applied holds from a step on: the sum of the windows open then.
  std::set<std::pair<std::int64_t, int>> points;  // (step, body) where a window opens or closes
  for (const Schedule::Force& f : schedule.forces) {
    if (f.start >= f.end) continue;
    points.insert({f.start, f.body});
    points.insert({f.end, f.body});
  }
  for (const auto& [step, body] : points) {
    if (step >= schedule.steps) continue;
    ForceChange c{step, body, {}};
    for (const Schedule::Force& f : schedule.forces) {
      if (f.body == body && f.start <= step && step < f.end) {
        for (int i = 0; i < 6; ++i) c.wrench[static_cast<size_t>(i)] += f.wrench[static_cast<size_t>(i)];
      }
    }
    forces_.push_back(c);  // sorted by step: std::set's order
  }
}

Policy::Policy(std::int64_t every) : every_(every) {
  if (every < 1 || every > kMaxSteps) {
    throw InvalidArgument("control_every must be from 1 to " + std::to_string(kMaxSteps) + ", got " +
                          std::to_string(every));
  }
}

void Policy::check_ctrl(std::int64_t step, const std::vector<double>& ctrl, int nu) {
  const std::string at = " at decision step " + std::to_string(step);
  if (ctrl.size() != static_cast<std::size_t>(nu)) {
    throw InvalidArgument("the policy must return " + std::to_string(nu) + " ctrl values, got " +
                          std::to_string(ctrl.size()) + at);
  }
  for (std::size_t a = 0; a < ctrl.size(); ++a) {
    if (!std::isfinite(ctrl[a])) {
      throw InvalidArgument("the policy returned a ctrl that is not finite" + at + ": ctrl[" + std::to_string(a) +
                            "] is " + python_float_repr(ctrl[a]));
    }
  }
}

void detail::check_schedule_run(std::int64_t steps, std::int64_t record_every) {
  if (record_every < 1 || record_every > kMaxRecordEvery) {
    throw InvalidArgument("record_every must be from 1 to " + std::to_string(kMaxRecordEvery) + ", got " +
                          std::to_string(record_every));
  }
  if (steps < 1 || steps > kMaxSteps) {
    throw InvalidArgument("steps must be from 1 to " + std::to_string(kMaxSteps) + ", got " + std::to_string(steps));
  }
}

RunRecord run_schedule(const mjModel* m, mjData* d, const ResolvedScenario& scenario, const Schedule& schedule,
                       std::int64_t record_every, RowSink* sink, RunControl* control, const RunInputs& inputs) {
  return detail::run_schedule_with(m, d, Recorder(m, scenario, schedule), schedule, record_every, sink, control,
                                   inputs);
}

RunRecord detail::run_schedule_with(const mjModel* m, mjData* d, const Recorder& recorder, const Schedule& schedule,
                                    std::int64_t record_every, RowSink* sink, RunControl* control,
                                    const RunInputs& inputs) {
  if (control && schedule.steps >= 1 && schedule.steps <= kMaxSteps) control->add_total(schedule.steps);
  return run_schedule_counted_elsewhere(m, d, recorder, schedule, record_every, sink, control, inputs);
}

RunRecord detail::run_schedule_counted_elsewhere(const mjModel* m, mjData* d, const Recorder& recorder,
                                                 const Schedule& schedule, std::int64_t record_every, RowSink* sink,
                                                 RunControl* control, const RunInputs& inputs,
                                                 const std::vector<StepObserver*>& watching, bool d_is_reset) {
  detail::check_schedule_run(schedule.steps, record_every);
  check_inputs(m, inputs, schedule.steps);
  if (sink == nullptr) check_kept_rows({{schedule.steps, record_every, recorder.width()}});
  RunRecord result;
  detail::KeepRows keep(result.trajectory);
  std::optional<EnergyAudit> audit;
  std::vector<StepObserver*> observers = watching;
  if (recorder.energy_column() >= 0) {
    std::vector<int> pushed;
    for (const Schedule::Force& f : schedule.forces) {
      if (std::find(pushed.begin(), pushed.end(), f.body) == pushed.end()) pushed.push_back(f.body);
    }
    observers.push_back(&audit.emplace(compat::as_int(m->nv), std::move(pushed), recorder.energy_column()));
  }
  detail::LoopResult loop = detail::run_loop(m, d, schedule, recorder, record_every, sink ? *sink : keep, control,
                                             inputs, observers, d_is_reset);
  result.columns = recorder.columns();
  result.schedule = schedule;
  result.timestep = loop.timestep;
  result.rows = loop.rows;
  result.final_row = std::move(loop.final_row);
  result.final_state = std::move(loop.final_state);
  result.warnings = std::move(loop.warnings);
  result.sim_time = loop.sim_time;
  if (audit) result.energy = audit->totals();
  return result;
}

}  // namespace simloop
