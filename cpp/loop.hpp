// The one loop every run steps in: the chapter's, a scenario's, a batch's,
// a policy's (internal to the library).
//
// It only reads what was decided before it started: the schedule (which
// ctrl and which forces change at which step, drawn from the seed up front),
// or the caller's own controls, or a policy's decisions. Per step:
//
//   write intent (ctrl), write interference (xfrc_applied), note the row,
//   mj_step, note what MuJoCo derived, watch for warnings and divergence.
//
// What a row holds is the recorder's business, what else is watched (the
// energy audit, the chapter's drift) the observers'. The steps run in
// chunks of RunControl::kChunkSteps inside one MuJoCo error guard each;
// between chunks the rows go to the sink and the control may stop the run.
#pragma once

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "divergence.hpp"
#include "mujoco_guard.hpp"
#include "simloop/control.hpp"
#include "simloop/errors.hpp"
#include "simloop/recorder.hpp"
#include "simloop/scenario.hpp"
#include "warning_counter.hpp"

namespace simloop::detail {

// What every stepping loop (run_loop, Sim, Episodes) watches after each
// mj_step: MuJoCo's warnings, counted, and simloop's divergence check.
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

// Watches a run step by step without changing it. `row` is the row being
// recorded at this step, or null.
class StepObserver {
 public:
  virtual ~StepObserver() = default;
  virtual void before_step(std::int64_t /*step*/, const mjModel* /*m*/, const mjData* /*d*/) noexcept {}
  virtual void after_step(std::int64_t /*step*/, const mjModel* /*m*/, mjData* /*d*/, double* /*row*/) noexcept {}
  // After the last step and the final mj_forward; `row` is the final row.
  virtual void at_end(const mjModel* /*m*/, const mjData* /*d*/, double* /*row*/) noexcept {}
};

// forward_keeping_state, leaving MuJoCo's warning counters as it found them
// (the step that follows derives the same state again and counts them).
void derive_uncounted(const mjModel* m, mjData* d);

// The observation before a decision, and the physics step after it.
//
// mj_step is mj_step1 (positions, velocities, their sensors) then mj_step2
// (actuation, constraints, integration), with the same bits, for every
// integrator but RK4. So the observation can be the first half of the next
// step: mj_step1 derives the state's poses, velocities and contacts,
// mj_fwdActuation the actuator forces of the ctrl in force, and the step
// after the decision is mj_step2 alone; one forward pass a decision less
// than forward_keeping_state then mj_step, and the same observation and run.
// mj_step1 may rewrite qpos and qvel in place (2.2 normalises quaternions
// there): what it wrote is held aside until mj_step2, so a row still reads
// the state as it entered the step. A whole forward pass remains for what
// the first half cannot give or would change: acceleration-stage sensors,
// RK4, a callback (it would see the ctrl before the decision), plugins (an
// actuator plugin's state would advance twice), a bad qpos or qvel (mj_step1
// would reset it where mj_step does). A warning MuJoCo raises deriving the
// state (a full contact buffer, say) counts once a step either way, as in an
// open-loop run: the whole forward pass leaves the warning counters as it
// found them, since the step derives the same state again.
class DecisionStep {
 public:
  DecisionStep(const mjModel* m, const RowRecorder& recorder);
  // Derives d's quantities for the observation; the step's inputs are
  // written. Inside MuJoCo's error guard.
  void observe(const mjModel* m, mjData* d);
  // The next physics step: the second half of the one observe() began, or
  // mj_step.
  void step(const mjModel* m, mjData* d) {
    observed_ = false;
    if (!begun_) {
      mj_step(m, d);
      return;
    }
    begun_ = false;
    if (held_) put_state(stepped_, d);
    mj_step2(m, d);
  }
  // Whether the last observe() began the next step (mj_step1).
  [[nodiscard]] bool begun() const noexcept { return begun_; }
  // The contacts d held when the step began: observe() runs the collision
  // again, which a row's ncon must not see (RowRecorder::before_step).
  [[nodiscard]] int entering_ncon(const mjData* d) const noexcept { return observed_ ? ncon_ : d->ncon; }

 private:
  void take_state(std::vector<double>& into, const mjData* d) const;
  void put_state(const std::vector<double>& from, mjData* d) const;
  int nq_, nv_;
  bool whole_forward_;     // the recorder reads the acceleration stage, RK4, plugins
  bool begun_ = false;     // mj_step1 has run on the state entering the next step
  bool held_ = false;      // mj_step1 rewrote qpos or qvel: stepped_ holds what it wrote
  bool observed_ = false;  // observe() has run since the last step: ncon_ is d->ncon before it
  int ncon_ = 0;
  std::vector<double> entering_;  // qpos and qvel as they entered the step
  std::vector<double> stepped_;   // and as mj_step1 left them
};

// What the loop leaves besides the rows it gave the sink.
struct LoopResult {
  std::int64_t rows = 0;            // rows recorded, kept or streamed
  std::vector<double> final_row;    // the last row
  std::vector<double> final_state;  // the full state at the end (state.hpp's layout)
  std::vector<Warning> warnings;    // MuJoCo's, then simloop's divergence
  double timestep = 0.0;
  double sim_time = 0.0;
};

// Writes the schedule's start (qpos, qvel; either may be empty: the reset's)
// into `d`, which mj_resetData has just reset, its quaternions made
// rotations again (noise or a caller's qpos may leave them off unit
// length). The caller then runs mj_forward.
inline void set_start(const mjModel* m, mjData* d, const Schedule::Start& start) {
  if (!start.qpos.empty()) {
    std::copy_n(start.qpos.data(), m->nq, d->qpos);
    mj_normalizeQuat(m, d->qpos);
  }
  if (!start.qvel.empty()) std::copy_n(start.qvel.data(), m->nv, d->qvel);
}

// Runs `schedule` on m and d (reset first, or set to inputs.initial_state),
// recording every `record_every`-th row with `recorder` into `rows`. The
// caller has checked the arguments (check_schedule_run, check_inputs). A
// MuJoCo error while stepping throws MujocoError saying the timestep and
// the steps it happened in; the control's stop throws Interrupted.
// `d_is_reset`: d is already as mj_resetData leaves it for m (a fresh Data,
// Data::fresh_for), which the loop then does not do again.
[[nodiscard]] LoopResult run_loop(const mjModel* m, mjData* d, const Schedule& schedule, const RowRecorder& recorder,
                                  std::int64_t record_every, RowSink& rows, RunControl* control,
                                  const RunInputs& inputs, const std::vector<StepObserver*>& observers = {},
                                  bool d_is_reset = false);

}  // namespace simloop::detail
