#include "simloop/sim.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "mujoco_compat.hpp"
#include "mujoco_guard.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"
#include "simloop/scenario.hpp"
#include "simloop/state.hpp"
#include "stepper.hpp"

namespace simloop {

// The stepping core every run steps with: its warnings, its divergence check.
struct Sim::Stepping : detail::Stepper {
  using Stepper::Stepper;
};

namespace {

void require_finite(double value, const char* what) {
  if (!std::isfinite(value)) {
    throw InvalidArgument(std::string(what) + " must be finite, got " + python_float_repr(value));
  }
}

// mjData's arrays by name, sized by the model: inputs and state writable,
// what MuJoCo derives read-only. (mjData's arrays are its pointers, so a
// const mjData still hands them out; read() only copies.)
ArrayView array_of(const mjModel* m, const mjData* d, std::string_view name) {
  using detail::compat::as_int;
  if (name == "qpos") return {d->qpos, as_int(m->nq), 0, true};
  if (name == "qvel") return {d->qvel, as_int(m->nv), 0, true};
  if (name == "ctrl") return {d->ctrl, as_int(m->nu), 0, true};
  if (name == "act") return {d->act, as_int(m->na), 0, true};
  if (name == "qfrc_applied") return {d->qfrc_applied, as_int(m->nv), 0, true};
  if (name == "xfrc_applied") return {d->xfrc_applied, as_int(m->nbody), 6, true};
  // Where the mocap bodies are: inputs, as ctrl is (row i: the body whose body_mocapid is i).
  if (name == "mocap_pos") return {d->mocap_pos, as_int(m->nmocap), 3, true};
  if (name == "mocap_quat") return {d->mocap_quat, as_int(m->nmocap), 4, true};
  if (name == "sensordata") return {d->sensordata, as_int(m->nsensordata), 0, false};
  if (name == "actuator_force") return {d->actuator_force, as_int(m->nu), 0, false};
  if (name == "xpos") return {d->xpos, as_int(m->nbody), 3, false};
  if (name == "xquat") return {d->xquat, as_int(m->nbody), 4, false};
  throw InvalidArgument("no Sim array named '" + std::string(name) + "'");
}

}  // namespace

Sim::Sim(const Model& model) : model_(model), data_(model), stepping_(std::make_shared<Stepping>(model.get())) {
  reset();
}

Sim::Sim(const Sim& other)
    : model_(other.owns_model_ ? other.model_.with_timestep(other.model_.timestep()) : other.model_),
      owns_model_(other.owns_model_),
      data_(other.model_),
      steps_(other.steps_),
      stepping_(std::make_shared<Stepping>(*other.stepping_)) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  const mjData* src = other.data_.get();
  detail::mujoco_call([&] { mj_copyData(d, m, src); });
}

void Sim::reset() {
  stepping_->reset(model_.get(), data_.get(), {});
  steps_ = 0;
}

void Sim::reset_to_keyframe(int key) {
  (void)checked_index(mjOBJ_KEY, key);
  stepping_->reset(model_.get(), data_.get(), {key});
  steps_ = 0;
}

int Sim::id(mjtObj type, const std::string& name) const { return object_id(model_.get(), type, name); }

int Sim::checked_index(mjtObj type, long long index) const { return checked_object_index(model_.get(), type, index); }

void Sim::set_timestep(double timestep) {
  check_positive_seconds("timestep", timestep);
  own_model()->opt.timestep = timestep;
}

mjModel* Sim::own_model() {
  if (!owns_model_) {
    model_ = model_.with_timestep(model_.timestep());  // mj_copyModel
    owns_model_ = true;
  }
  // The copy is this Sim's alone: nothing else was given it before now, and
  // what is given it from now on (model(), views) reads what the Sim writes.
  return const_cast<mjModel*>(model_.get());
}

void Sim::set_ctrl(double value) {
  require_finite(value, "ctrl");
  if (model_.get()->nu < 1) throw InvalidArgument("ctrl: the model has no actuator (ctrl[0] does not exist)");
  data_.get()->ctrl[0] = value;
}

double Sim::ctrl() const {
  if (model_.get()->nu < 1) throw InvalidArgument("ctrl: the model has no actuator (ctrl[0] does not exist)");
  return data_.get()->ctrl[0];
}

void Sim::set_ctrl(const double* values, std::size_t count) {
  const auto nu = static_cast<std::size_t>(model_.get()->nu);
  if (count != nu) {
    throw InvalidArgument("ctrl must have nu = " + std::to_string(nu) + " values (one per actuator), got " +
                          std::to_string(count));
  }
  for (std::size_t i = 0; i < count; ++i) {
    if (!std::isfinite(values[i])) {
      throw InvalidArgument("ctrl[" + std::to_string(i) + "] must be finite, got " + python_float_repr(values[i]));
    }
  }
  std::copy(values, values + count, data_.get()->ctrl);
}

void Sim::apply_wrench(int body, const std::array<double, 3>* force, const std::array<double, 3>* torque) {
  (void)checked_index(mjOBJ_BODY, body);
  if (force) {
    for (double f : *force) require_finite(f, "force");
  }
  if (torque) {
    for (double t : *torque) require_finite(t, "torque");
  }
  double* slot = data_.get()->xfrc_applied + 6 * body;
  if (force) std::copy(force->begin(), force->end(), slot);
  if (torque) std::copy(torque->begin(), torque->end(), slot + 3);
}

void Sim::clear_forces() noexcept { std::fill_n(data_.get()->xfrc_applied, 6 * model_.get()->nbody, 0.0); }

void Sim::forward() {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  detail::mujoco_call([&] { forward_keeping_state(m, d); });
}

std::vector<double> Sim::state() const { return get_state(model_.get(), data_.get()); }

std::vector<double> Sim::mujoco_state() const {
  const mjModel* m = model_.get();
  if (mujoco_state_size(m) == 0) {
    throw InvalidArgument("MuJoCo's own state (mj_getState) needs MuJoCo 3.3 or later; this simloop is built on " +
                          detail::compat::version_string() + ": use simloop's state");
  }
  std::vector<double> state(mujoco_state_size(m));
  detail::compat::get_mujoco_state(m, data_.get(), state.data());
  return state;
}

std::size_t Sim::state_size() const noexcept { return simloop::state_size(model_.get()); }

std::vector<std::pair<std::string, std::size_t>> Sim::state_layout() const {
  return simloop::state_layout(model_.get());
}

void Sim::set_state(const double* state, std::size_t size) {
  const mjModel* m = model_.get();
  if (!takes_state_size(m, size)) {
    throw InvalidArgument("state must have " + state_sizes_text(m) + " for this model, got " + std::to_string(size));
  }
  mjData* d = data_.get();
  detail::mujoco_call([&] { simloop::set_state(m, d, state, size); });
}

std::array<double, 6> Sim::body_velocity(int body) const {
  (void)checked_index(mjOBJ_BODY, body);
  std::array<double, 6> velocity{};
  const mjModel* m = model_.get();
  const mjData* d = data_.get();
  double* out = velocity.data();
  detail::mujoco_call([&] { mj_objectVelocity(m, d, mjOBJ_BODY, body, out, 0); });
  return velocity;
}

void Sim::check_steps(std::int64_t n) { check_count("n", n, kMaxSteps); }

void Sim::step(std::int64_t n, RunControl* control) {
  check_steps(n);
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  if (control) control->add_total(n);
  // Nothing around each step: the caller writes the inputs between calls.
  stepping_->run(m, d, steps_, steps_ + n, detail::StepHooks{}, control);
}

std::vector<Contact> Sim::contacts() const {
  const mjModel* m = model_.get();
  const mjData* d = data_.get();
  std::vector<Contact> out;
  out.reserve(static_cast<std::size_t>(d->ncon));
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    Contact contact;
    contact.dist = c.dist;
    std::copy_n(c.pos, 3, contact.pos.data());
    std::copy_n(c.frame, 9, contact.frame.data());
    const auto side = [m](int geom, std::string& name, int& id, std::string& body, int& body_id) {
      if (geom < 0 || geom >= m->ngeom) return;  // a flex's side of the contact
      id = geom;
      name = object_name(m, mjOBJ_GEOM, geom);
      body_id = m->geom_bodyid[geom];
      body = object_name(m, mjOBJ_BODY, body_id);
    };
    side(c.geom1, contact.geom1, contact.geom1_id, contact.body1, contact.body1_id);
    side(c.geom2, contact.geom2, contact.geom2_id, contact.body2, contact.body2_id);
    double* force = contact.force.data();
    detail::mujoco_call([&] { mj_contactForce(m, d, i, force); });
    out.push_back(std::move(contact));
  }
  return out;
}

ArrayView Sim::array(std::string_view name) { return array_of(model_.get(), data_.get(), name); }

FieldView Sim::data_field(std::string_view name) {
  FieldView field = simloop::data_field(model_.get(), data_.get(), name);
  if (filled_on_request(name)) {
    detail::mujoco_call([&] { fill_derived(model_.get(), data_.get(), name); });
  }
  return field;
}

FieldView Sim::model_field(std::string_view name) const { return simloop::model_field(model_.get(), name); }

FieldView Sim::writable_model_field(std::string_view name) {
  (void)simloop::model_field(model_.get(), name);  // an unknown name: refused first, and before any copy
  if (!model_field_writable(name)) {
    throw InvalidArgument("mjModel's " + std::string(name) +
                          " is read-only here: a Sim lets you write the parameters a trainer randomises "
                          "(masses, inertias, friction, contact softness, damping, armature, stiffness, "
                          "actuator gains, biases, gears and ranges, colours)");
  }
  return simloop::model_field(own_model(), name);
}

std::vector<double> Sim::read(std::string_view name, long long start, long long count) const {
  const ArrayView view = array_of(model_.get(), data_.get(), name);
  const long long size = static_cast<long long>(view.rows) * std::max(view.width, 1);
  if (start < 0 || count < 0 || count > size - start) {
    throw InvalidArgument(std::string(name) + " has " + std::to_string(size) + " values: cannot read " +
                          std::to_string(count) + " from index " + std::to_string(start));
  }
  return std::vector<double>(view.data + start, view.data + start + count);
}

std::vector<Warning> Sim::warnings() const { return stepping_->health().warnings(); }

}  // namespace simloop
