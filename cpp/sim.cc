#include "simloop/sim.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "mujoco_guard.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "warning_counter.hpp"

namespace simloop {

struct Sim::Counter : detail::WarningCounter {};

namespace {

void require_finite(double value, const char* what) {
  if (!std::isfinite(value)) {
    throw InvalidArgument(std::string(what) + " must be finite, got " + python_float_repr(value));
  }
}

}  // namespace

Sim::Sim(const Model& model) : model_(model), data_(model) {
  (void)model_.layout();  // the chapter's Sim reads the box and the pusher: refuse other scenes now
  reset();
}

void Sim::reset() {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  detail::mujoco_call([&] {
    mj_resetData(m, d);
    mj_forward(m, d);
  });
  steps_ = 0;
  counter_ = std::make_shared<Counter>();
}

void Sim::set_timestep(double timestep) { model_ = model_.with_timestep(timestep); }

void Sim::set_ctrl(double value) {
  require_finite(value, "ctrl");
  data_.get()->ctrl[0] = value;
}

void Sim::apply_force(const std::array<double, 3>& force) {
  for (double f : force) require_finite(f, "force");
  double* slot = data_.get()->xfrc_applied + 6 * model_.layout().box_body;
  for (int i = 0; i < 3; ++i) slot[i] = force[i];
}

void Sim::clear_force() noexcept {
  double* slot = data_.get()->xfrc_applied + 6 * model_.layout().box_body;
  for (int i = 0; i < 3; ++i) slot[i] = 0.0;
}

std::array<double, 3> Sim::applied_force() const noexcept {
  const double* slot = data_.get()->xfrc_applied + 6 * model_.layout().box_body;
  return {slot[0], slot[1], slot[2]};
}

void Sim::step(std::int64_t n, RunControl* control) {
  if (n < 1) throw InvalidArgument("n must be at least 1, got " + std::to_string(n));
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  if (control) control->add_total(n);
  for (std::int64_t done = 0; done < n;) {
    const std::int64_t chunk = std::min(n - done, RunControl::kChunkSteps);
    for (std::int64_t i = 0; i < chunk; ++i) {
      detail::mujoco_call([&] { mj_step(m, d); });
      counter_->after_step(d, steps_);
      ++steps_;
    }
    done += chunk;
    if (control) control->advance(chunk);
  }
}

std::array<double, 3> Sim::box_position() const noexcept {
  const double* q = data_.get()->qpos + model_.layout().box_qposadr;
  return {q[0], q[1], q[2]};
}

std::array<double, 4> Sim::box_quaternion() const noexcept {
  const double* q = data_.get()->qpos + model_.layout().box_qposadr + 3;
  return {q[0], q[1], q[2], q[3]};
}

std::array<double, 3> Sim::box_velocity() const noexcept {
  const double* v = data_.get()->qvel + model_.layout().box_dofadr;
  return {v[0], v[1], v[2]};
}

double Sim::pusher_x() const noexcept { return data_.get()->qpos[model_.layout().pusher_qposadr]; }

double Sim::pusher_velocity() const noexcept { return data_.get()->qvel[model_.layout().pusher_dofadr]; }

std::vector<Contact> Sim::contacts() const {
  const mjModel* m = model_.get();
  const mjData* d = data_.get();
  std::vector<Contact> out;
  out.reserve(static_cast<std::size_t>(d->ncon));
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    const char* g1 = mj_id2name(m, mjOBJ_GEOM, c.geom1);
    const char* g2 = mj_id2name(m, mjOBJ_GEOM, c.geom2);
    out.push_back({g1 ? g1 : "", g2 ? g2 : "", c.dist, {c.pos[0], c.pos[1], c.pos[2]}});
  }
  return out;
}

std::vector<Warning> Sim::warnings() const { return counter_->warnings(); }

PusherTrack pusher_track(const Model& model) {
  const mjModel* m = model.get();
  const SceneLayout& at = model.layout();
  Data scratch(model);
  mjData* d = scratch.get();
  detail::mujoco_call([&] {
    mj_resetData(m, d);
    mj_kinematics(m, d);
  });
  PusherTrack track;
  for (int i = 0; i < 3; ++i) track.rest_position[i] = d->xpos[3 * at.pusher_body + i];
  if (m->jnt_type[at.pusher_joint] == mjJNT_SLIDE) {
    for (int i = 0; i < 3; ++i) track.axis[i] = d->xaxis[3 * at.pusher_joint + i];
  }
  track.q0 = m->qpos0[at.pusher_qposadr];
  return track;
}

}  // namespace simloop
