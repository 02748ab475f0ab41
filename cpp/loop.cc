#include "loop.hpp"

#include <algorithm>
#include <cstring>
#include <sstream>

#include "mujoco_compat.hpp"
#include "run_detail.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/state.hpp"

namespace simloop::detail {

MujocoError stepping_error(const mjModel* m, std::int64_t from, std::int64_t to, const MujocoError& e) {
  std::ostringstream msg;
  msg << "running the model at timestep " << python_float_repr(m->opt.timestep) << " s, in steps " << from << " to "
      << to << ": " << e.what();
  return MujocoError(msg.str());
}

DecisionStep::DecisionStep(const mjModel* m, const RowRecorder& recorder)
    : nq_(compat::as_int(m->nq)),
      nv_(compat::as_int(m->nv)),
      whole_forward_(recorder.reads_acceleration_stage() || m->opt.integrator == mjINT_RK4 || compat::has_plugins(m)),
      entering_(static_cast<std::size_t>(nq_ + nv_)),
      stepped_(entering_.size()) {}

void DecisionStep::take_state(std::vector<double>& into, const mjData* d) const {
  std::copy_n(d->qpos, nq_, into.begin());
  std::copy_n(d->qvel, nv_, into.begin() + nq_);
}

void DecisionStep::put_state(const std::vector<double>& from, mjData* d) const {
  std::copy_n(from.begin(), nq_, d->qpos);
  std::copy_n(from.begin() + nq_, nv_, d->qvel);
}

void derive_uncounted(const mjModel* m, mjData* d) {
  mjWarningStat counted[mjNWARNING];
  std::copy_n(d->warning, mjNWARNING, counted);
  forward_keeping_state(m, d);
  std::copy_n(counted, mjNWARNING, d->warning);
}

void DecisionStep::observe(const mjModel* m, mjData* d) {
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

LoopResult run_loop(const mjModel* m, mjData* d, const Schedule& schedule, const RowRecorder& recorder,
                    std::int64_t record_every, RowSink& rows, RunControl* control, const RunInputs& inputs,
                    const std::vector<StepObserver*>& observers, bool d_is_reset) {
  Policy* const policy = inputs.policy;
  // The caller's controls, or a policy, replace the schedule's ctrl changes.
  ScheduledInputs scheduled(schedule, policy == nullptr && inputs.controls == nullptr);
  const double* own_controls = inputs.controls;
  const int nu = compat::as_int(m->nu);
  const std::int64_t steps = schedule.steps;
  const int width = recorder.width();

  LoopResult result;
  result.timestep = m->opt.timestep;
  result.rows = Trajectory::rows_for(steps, record_every);
  rows.describe(recorder.columns());
  rows.start(width, result.rows);
  RowBlock block(width, std::min(result.rows, RunControl::kChunkSteps / record_every + 2));
  StepHealth health(m);
  // Decision steps: 0, K, 2K, ... with a policy; none (the run's end) without.
  std::int64_t next_decision = policy ? 0 : steps;
  std::vector<double> observation(policy ? static_cast<std::size_t>(width) : 0);
  DecisionStep decision(m, recorder);
  // RK4's later stages leave the poses, contacts and forces of a state the
  // row does not hold (its last stage's): a recorded row derives them from
  // its own state before the step instead of reading them after it.
  const bool derive_before_step = m->opt.integrator == mjINT_RK4;

  // mj_forward fills in the derived state (poses, contacts) without
  // advancing time, so row 0 is the true state at t = 0.
  guarded_steps(m, 0, 0, [&] {
    if (!d_is_reset) mj_resetData(m, d);
    if (inputs.initial_state) {
      set_state(m, d, inputs.initial_state);  // forward, keeping the state as given
    } else {
      set_start(m, d, schedule.start);
      mj_forward(m, d);
    }
  });
  std::int64_t until_record = 0;  // counts down to the next recorded step
  for (std::int64_t step = 0; step < steps;) {
    if (step == next_decision) {
      // Outside MuJoCo's guard: the policy may throw (a Python exception).
      guarded_steps(m, step, step, [&] {
        scheduled.write(step, d);
        decision.observe(m, d);
      });
      recorder.before_step(observation.data(), step, m, d, true, decision.entering_ncon(d));
      recorder.after_step(observation.data(), m, d);
      policy->decide(step, observation.data(), width, d->ctrl, nu);
      next_decision = steps - step > policy->every() ? step + policy->every() : steps;
    }
    const std::int64_t chunk_start = step;
    const std::int64_t chunk_end = std::min({steps, step + RunControl::kChunkSteps, next_decision});
    guarded_steps(m, chunk_start, chunk_end - 1, [&] {
      for (; step < chunk_end; ++step) {
        // The rhythm: write intent, write interference, step. The schedule
        // says what changes at this step; everything else persists.
        scheduled.write(step, d);
        if (own_controls) std::copy_n(own_controls + step * nu, nu, d->ctrl);
        double* row = nullptr;
        if (until_record-- == 0) {
          row = block.next();
          recorder.before_step(row, step, m, d, true, decision.entering_ncon(d));
          if (derive_before_step) {
            derive_uncounted(m, d);
            recorder.after_step(row, m, d);
          }
          until_record = record_every - 1;
        }
        for (StepObserver* o : observers) o->before_step(step, m, d);
        decision.step(m, d);  // mj_step (its second half after a decision's observation)
        health.after_step(d, step);
        if (row && !derive_before_step) recorder.after_step(row, m, d);
        for (StepObserver* o : observers) o->after_step(step, m, d, row);
      }
    });
    block.flush_to(rows);
    if (control) control->advance(chunk_end - chunk_start);
  }
  double* last = block.next();
  recorder.before_step(last, steps, m, d, false, d->ncon);
  // Before mj_forward, which would overwrite the warmstart the next step needs.
  result.final_state = get_state(m, d);
  // MuJoCo derives a state's quantities (and its energy) during a step; the
  // final state has had none, so a forward pass (no time advances) does it.
  guarded_steps(m, steps, steps, [&] { mj_forward(m, d); });
  recorder.after_step(last, m, d);
  for (StepObserver* o : observers) o->at_end(m, d, last);
  result.final_row.assign(last, last + width);
  block.flush_to(rows);

  result.warnings = health.warnings();
  result.sim_time = d->time;
  return result;
}

}  // namespace simloop::detail
