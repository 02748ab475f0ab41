// The stepping core (internal to the library): every physics step a run, a
// batch, a Sim or an episode takes, and every reset, goes through here.
//
// Stepper::reset puts a state where a run starts; Stepper::run takes steps
// in chunks of RunControl::kChunkSteps, each inside one MuJoCo error guard,
// and after each step counts MuJoCo's warnings and checks for divergence
// (StepHealth). Stepper::observe is the observation before a decision, made
// the first half of the next step. What happens around each step (inputs
// written, rows recorded) is the caller's, passed in as StepHooks. So
// mj_step, mj_step1, mj_step2 and mj_resetData are called here and nowhere
// else in the library.
#pragma once

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "divergence.hpp"
#include "mujoco_guard.hpp"
#include "simloop/control.hpp"
#include "simloop/errors.hpp"
#include "simloop/scenario.hpp"
#include "warning_counter.hpp"

namespace simloop::detail {

// What every stepping loop watches after each step: MuJoCo's warnings,
// counted, and simloop's divergence check.
class StepHealth {
 public:
  explicit StepHealth(const mjModel* m) : divergence_(m) {}
  void after_step(mjData* d, std::int64_t step) noexcept {
    // Before the counter empties them: after these MuJoCo reset the state.
    reset_by_mujoco_ = reset_by_mujoco_ || d->warning[mjWARN_BADQPOS].number > 0 ||
                       d->warning[mjWARN_BADQVEL].number > 0 || d->warning[mjWARN_BADQACC].number > 0;
    warnings_.after_step(d, step);
    divergence_.after_step(d, step);
  }
  // MuJoCo reset a bad state, or a free body fell through the floor.
  [[nodiscard]] bool broken() const noexcept { return reset_by_mujoco_ || divergence_.diverged(); }
  // MuJoCo's warnings, then the divergence's if any.
  [[nodiscard]] std::vector<Warning> warnings() const {
    std::vector<Warning> out = warnings_.warnings();
    if (divergence_.diverged()) out.push_back(divergence_.warning());
    return out;
  }

 private:
  WarningCounter warnings_;
  DivergenceCheck divergence_;
  bool reset_by_mujoco_ = false;
};

// A MuJoCo error `e` while running steps `from` to `to`, saying so and the
// timestep, on one line.
[[nodiscard]] MujocoError stepping_error(const mjModel* m, std::int64_t from, std::int64_t to, const MujocoError& e);

// Runs `steps` (MuJoCo calls for steps `from` to `to`) inside one MuJoCo
// error guard; a MuJoCo error throws stepping_error.
template <class Steps>
void guarded_steps(const mjModel* m, std::int64_t from, std::int64_t to, Steps&& steps) {
  try {
    mujoco_call(steps);
  } catch (const MujocoError& e) {
    throw stepping_error(m, from, to, e);
  }
}

// forward_keeping_state, leaving MuJoCo's warning counters as it found them
// (the step that follows derives the same state again and counts them).
void derive_uncounted(const mjModel* m, mjData* d);

// What a caller does around each step (Stepper::run's hooks): these do
// nothing, and a caller's hooks hide the ones they need. before_step and
// after_step run inside MuJoCo's error guard, whose errors jump out without
// unwinding; chunk_done runs after each chunk, outside it.
struct StepHooks {
  void before_step(std::int64_t /*step*/, mjData* /*d*/) noexcept {}
  void after_step(std::int64_t /*step*/, mjData* /*d*/) noexcept {}
  void chunk_done() {}
};

// Where a reset puts the state: the model's initial state (or keyframe
// `keyframe`'s), with `start` written over it; or a whole state given.
struct StartAt {
  int keyframe = -1;                       // mj_resetDataKeyframe's, or -1: the model's own
  const Schedule::Start* start = nullptr;  // qpos, qvel over the reset's (either may be empty)
  const double* state = nullptr;           // instead: a full state (state.hpp's layout), kept as given
  bool d_is_reset = false;                 // d is as mj_resetData left it (a fresh Data): not again
  // Something reads the state at t = 0 (a row, an observer, a policy): its
  // derived quantities are made then. Else a whole state is put in place
  // as it is, and the first step derives them, as mujoco.rollout's does.
  bool read_at_start = true;
  // The state's length: state_size(m), or MuJoCo's own state's (state.hpp).
  std::size_t state_size = 0;
};

class Stepper {
 public:
  // observe_acceleration: the observations read the acceleration stage (a
  // recorder's sensors), which the first half of a step does not derive.
  explicit Stepper(const mjModel* m, bool observe_acceleration = false);

  // The one reset: d to `at`, then MuJoCo's derived quantities for it (so
  // every read is the true state at t = 0); the warnings and divergence
  // counted from here. A MuJoCo error throws stepping_error for step 0.
  void reset(const mjModel* m, mjData* d, const StartAt& at);

  // Steps `step` up to `end` (step ends at `end`, or after the step that
  // broke the state if `stop_when_broken`): per step, hooks.before_step,
  // the physics step (the rest of the one observe() began, or mj_step), the
  // health check, hooks.after_step; after each chunk, hooks.chunk_done and
  // control->advance (which may throw Interrupted). A MuJoCo error throws
  // stepping_error naming the chunk's steps; `step` counts the steps taken.
  template <class Hooks>
  void run(const mjModel* m, mjData* d, std::int64_t& step, std::int64_t end, Hooks&& hooks, RunControl* control,
           bool stop_when_broken = false) {
    bool stopped = false;
    while (step < end && !stopped) {
      const std::int64_t chunk_start = step;
      const std::int64_t chunk_end = std::min(end, step + RunControl::kChunkSteps);
      guarded_steps(m, chunk_start, chunk_end - 1, [&] {
        for (; step < chunk_end && !stopped; ++step) {
          hooks.before_step(step, d);
          physics_step(m, d);
          health_.after_step(d, step);
          hooks.after_step(step, d);
          stopped = stop_when_broken && health_.broken();
        }
      });
      hooks.chunk_done();
      if (control) control->advance(step - chunk_start);
    }
  }

  // The observation before a decision at `step`, its inputs written:
  // derives d's quantities for it. A MuJoCo error throws stepping_error.
  //
  // mj_step is mj_step1 (positions, velocities, their sensors) then mj_step2
  // (actuation, constraints, integration), with the same bits, for every
  // integrator but RK4. So the observation can be the first half of the
  // next step: mj_step1 derives the state's poses, velocities and contacts,
  // mj_fwdActuation the actuator forces of the ctrl in force, and the step
  // after the decision is mj_step2 alone; one forward pass a decision less
  // than forward_keeping_state then mj_step, and the same observation and
  // run. mj_step1 may rewrite qpos and qvel in place (2.2 normalises
  // quaternions there): what it wrote is held aside until mj_step2, so a
  // row still reads the state as it entered the step. A whole forward pass
  // remains for what the first half cannot give or would change:
  // acceleration-stage sensors, RK4, a callback (it would see the ctrl
  // before the decision), plugins (an actuator plugin's state would advance
  // twice), a bad qpos or qvel (mj_step1 would reset it where mj_step does).
  // A warning MuJoCo raises deriving the state (a full contact buffer, say)
  // counts once a step either way, as in an open-loop run: the whole
  // forward pass leaves the warning counters as it found them, since the
  // step derives the same state again.
  void observe(const mjModel* m, mjData* d, std::int64_t step);
  // What MuJoCo derives from the state without stepping (the last state,
  // which no step has derived): mj_forward, guarded for `step`.
  void derive(const mjModel* m, mjData* d, std::int64_t step) const;

  [[nodiscard]] const StepHealth& health() const noexcept { return health_; }
  // Whether the last observe() began the next step (mj_step1).
  [[nodiscard]] bool begun() const noexcept { return begun_; }
  // The contacts d held when the step began: observe() runs the collision
  // again, which a row's ncon must not see (RowRecorder::before_step).
  [[nodiscard]] int entering_ncon(const mjData* d) const noexcept { return observed_ ? ncon_ : d->ncon; }

 private:
  void physics_step(const mjModel* m, mjData* d);
  void begin_step(const mjModel* m, mjData* d);
  void take_state(std::vector<double>& into, const mjData* d) const;
  void put_state(const std::vector<double>& from, mjData* d) const;

  bool observe_acceleration_;
  StepHealth health_;
  int nq_ = 0, nv_ = 0;
  bool whole_forward_ = false;  // observations take a whole forward pass: acceleration stage, RK4, plugins
  bool begun_ = false;          // mj_step1 has run on the state entering the next step
  bool held_ = false;           // mj_step1 rewrote qpos or qvel: stepped_ holds what it wrote
  bool observed_ = false;       // observe() has run since the last step: ncon_ is d->ncon before it
  int ncon_ = 0;
  std::vector<double> entering_;  // qpos and qvel as they entered the step
  std::vector<double> stepped_;   // and as mj_step1 left them
};

}  // namespace simloop::detail
