#include "stepper.hpp"

#include <algorithm>
#include <cstring>
#include <sstream>

#include "mujoco_compat.hpp"
#include "simloop/number_format.hpp"
#include "simloop/state.hpp"

namespace simloop::detail {

MujocoError stepping_error(const mjModel* m, std::int64_t from, std::int64_t to, const MujocoError& e) {
  std::ostringstream msg;
  msg << "running the model at timestep " << python_float_repr(m->opt.timestep) << " s, in steps " << from << " to "
      << to << ": " << e.what();
  return MujocoError(msg.str());
}

void derive_uncounted(const mjModel* m, mjData* d) {
  mjWarningStat counted[mjNWARNING];
  std::copy_n(d->warning, mjNWARNING, counted);
  forward_keeping_state(m, d);
  std::copy_n(counted, mjNWARNING, d->warning);
}

Stepper::Stepper(const mjModel* m, bool observe_acceleration)
    : observe_acceleration_(observe_acceleration), health_(m) {}

void Stepper::reset(const mjModel* m, mjData* d, const StartAt& at) {
  // What this run's stepping knows of the model: a reset may be the first
  // for a model another reset's was copied from (an episode's parameters).
  health_ = StepHealth(m);
  nq_ = compat::as_int(m->nq);
  nv_ = compat::as_int(m->nv);
  whole_forward_ = observe_acceleration_ || m->opt.integrator == mjINT_RK4 || compat::has_plugins(m);
  entering_.resize(static_cast<std::size_t>(nq_ + nv_));
  stepped_.resize(entering_.size());
  begun_ = held_ = observed_ = false;
  guarded_steps(m, 0, 0, [&] {
    if (at.state) {
      // A full state is everything mj_step reads that is not the model
      // (state.hpp), so no reset first: of the last run only MuJoCo's
      // warning counters would be left (as mujoco.rollout, which zeroes
      // them). mj_resetData was about 2 % of a 100-step PushT run.
      std::fill_n(d->warning, mjNWARNING, mjWarningStat{});
      // (A sleeping tree's poses the step does not derive: they must be.)
      const bool awake = at.state_size != compat::state_size(m) || compat::state_all_awake(m, at.state);
      if (at.read_at_start || !awake) {
        simloop::set_state(m, d, at.state, at.state_size);  // forward, keeping the state as given
      } else {
        simloop::put_state(m, d, at.state, at.state_size);
      }
      return;
    }
    const int keyframe = at.start && at.start->keyframe >= 0 ? at.start->keyframe : at.keyframe;
    if (keyframe >= 0) {
      mj_resetDataKeyframe(m, d, keyframe);
    } else if (!at.d_is_reset) {
      mj_resetData(m, d);
    }
    if (at.start && !at.start->qpos.empty()) {
      // Noise or a caller's qpos may leave quaternions off unit length.
      std::copy_n(at.start->qpos.data(), m->nq, d->qpos);
      mj_normalizeQuat(m, d->qpos);
    }
    if (at.start && !at.start->qvel.empty()) std::copy_n(at.start->qvel.data(), m->nv, d->qvel);
    if (at.start) {
      for (const Schedule::Start::MocapPos& g : at.start->goals)
        std::copy_n(g.pos.data(), 3, d->mocap_pos + 3 * g.mocap);
    }
    mj_forward(m, d);
  });
}

void Stepper::take_state(std::vector<double>& into, const mjData* d) const {
  std::copy_n(d->qpos, nq_, into.begin());
  std::copy_n(d->qvel, nv_, into.begin() + nq_);
}

void Stepper::put_state(const std::vector<double>& from, mjData* d) const {
  std::copy_n(from.begin(), nq_, d->qpos);
  std::copy_n(from.begin() + nq_, nv_, d->qvel);
}

void Stepper::physics_step(const mjModel* m, mjData* d) {
  observed_ = false;
  if (!begun_) {
    mj_step(m, d);
    return;
  }
  begun_ = false;
  if (held_) put_state(stepped_, d);
  mj_step2(m, d);
}

void Stepper::observe(const mjModel* m, mjData* d, std::int64_t step) {
  guarded_steps(m, step, step, [&] { begin_step(m, d); });
}

void Stepper::begin_step(const mjModel* m, mjData* d) {
  begun_ = false;
  observed_ = true;
  ncon_ = d->ncon;
  take_state(entering_, d);
  const bool callbacks = mjcb_control || mjcb_passive || mjcb_sensor || mjcb_act_dyn || mjcb_act_gain ||
                         mjcb_act_bias || mjcb_contactfilter;
  const bool bad = std::any_of(entering_.begin(), entering_.end(), [](double x) { return mju_isBad(x) != 0; });
  if (whole_forward_ || callbacks || bad) {
    derive_uncounted(m, d);
    return;
  }
  mj_step1(m, d);
  mj_fwdActuation(m, d);  // (mj_step2 computes them again with the decided ctrl)
  take_state(stepped_, d);
  held_ = std::memcmp(stepped_.data(), entering_.data(), entering_.size() * sizeof(double)) != 0;  // bitwise
  if (held_) put_state(entering_, d);
  begun_ = true;
}

void Stepper::derive(const mjModel* m, mjData* d, std::int64_t step) const {
  guarded_steps(m, step, step, [&] { mj_forward(m, d); });
}

}  // namespace simloop::detail
