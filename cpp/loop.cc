#include "loop.hpp"

#include <algorithm>
#include <limits>

#include "mujoco_compat.hpp"
#include "run_detail.hpp"
#include "simloop/state.hpp"
#include "stepper.hpp"

namespace simloop::detail {

namespace {

// The loop's work around each physics step (inside MuJoCo's guard): the
// step's inputs, its row when one is due, the observers.
struct Rhythm {
  Rhythm(const mjModel* model, ScheduledInputs& inputs, const RunInputs& run_inputs, const RowRecorder& row_recorder,
         std::int64_t every, const std::vector<StepObserver*>& watching, RowBlock& row_block, RowSink& sink,
         const Stepper& stepper)
      : m(model),
        scheduled(inputs),
        own_controls(run_inputs.controls),
        nu(compat::as_int(model->nu)),
        recorder(row_recorder),
        record_every(every),
        derive_before_step(model->opt.integrator == mjINT_RK4),
        observers(watching),
        block(row_block),
        rows(sink),
        core(stepper) {}

  const mjModel* m;
  ScheduledInputs& scheduled;
  const double* own_controls;  // the caller's, (steps, nu); or null
  int nu;
  const RowRecorder& recorder;
  std::int64_t record_every;
  // RK4's later stages leave the poses, contacts and forces of a state the
  // row does not hold (its last stage's): a recorded row derives them from
  // its own state before the step instead of reading them after it.
  bool derive_before_step;
  const std::vector<StepObserver*>& observers;
  RowBlock& block;
  RowSink& rows;
  const Stepper& core;            // the count of contacts the step began with
  std::int64_t until_record = 0;  // counts down to the next recorded step
  double* row = nullptr;          // this step's, if it is recorded

  void before_step(std::int64_t step, mjData* d) {
    // The rhythm: write intent, write interference, step. The schedule
    // says what changes at this step; everything else persists.
    scheduled.write(step, d);
    if (own_controls) std::copy_n(own_controls + step * nu, nu, d->ctrl);
    row = nullptr;
    if (until_record-- == 0) {
      row = block.next();
      recorder.before_step(row, step, m, d, true, core.entering_ncon(d));
      if (derive_before_step) {
        derive_uncounted(m, d);
        recorder.after_step(row, m, d);
      }
      until_record = record_every - 1;
    }
    for (StepObserver* o : observers) o->before_step(step, m, d);
  }
  void after_step(std::int64_t step, mjData* d) {
    if (row && !derive_before_step) recorder.after_step(row, m, d);
    for (StepObserver* o : observers) o->after_step(step, m, d, row);
  }
  void chunk_done() { block.flush_to(rows); }
};

}  // namespace

LoopResult run_loop(const mjModel* m, mjData* d, const Schedule& schedule, const RowRecorder& recorder,
                    std::int64_t record_every, RowSink& rows, RunControl* control, const RunInputs& inputs,
                    const std::vector<StepObserver*>& observers, bool d_is_reset) {
  Policy* const policy = inputs.policy;
  const int nu = compat::as_int(m->nu);
  const std::int64_t steps = schedule.steps;
  const int width = recorder.width();

  LoopResult result;
  result.timestep = m->opt.timestep;
  result.rows = Trajectory::rows_for(steps, record_every);
  rows.describe(recorder.columns());
  rows.start(width, result.rows);
  RowBlock block(width, std::min(result.rows, RunControl::kChunkSteps / record_every + 2));
  // The caller's controls, or a policy, replace the schedule's ctrl changes.
  ScheduledInputs scheduled(schedule, policy == nullptr && inputs.controls == nullptr);
  Stepper core(m, recorder.reads_acceleration_stage());
  Rhythm rhythm(m, scheduled, inputs, recorder, record_every, observers, block, rows, core);
  // A sink that keeps only the final row, with nothing watching the rows
  // (a metrics-only batch), is given only that one: no other is recorded.
  const bool record_rows = rows.keeps_rows() || !observers.empty();
  if (!record_rows) rhythm.until_record = std::numeric_limits<std::int64_t>::max();
  // Decision steps: 0, K, 2K, ... with a policy; none (the run's end) without.
  std::int64_t next_decision = policy ? 0 : steps;
  std::vector<double> observation(policy ? static_cast<std::size_t>(width) : 0);
  std::vector<double> decision;

  // Row 0 is the true state at t = 0.
  core.reset(
      m, d,
      {-1, &schedule.start, inputs.initial_state, d_is_reset, record_rows || policy != nullptr, inputs.state_size});
  for (std::int64_t step = 0; step < steps;) {
    if (step == next_decision) {
      scheduled.write(step, d);  // the disturbances the observation sees
      core.observe(m, d, step);
      recorder.before_step(observation.data(), step, m, d, true, core.entering_ncon(d));
      recorder.after_step(observation.data(), m, d);
      // Outside MuJoCo's guard: the policy may throw (a Python exception).
      decision.assign(d->ctrl, d->ctrl + nu);
      policy->decide(step, observation.data(), width, decision);
      Policy::check_ctrl(step, decision, nu);
      std::copy(decision.begin(), decision.end(), d->ctrl);
      next_decision = steps - step > policy->every() ? step + policy->every() : steps;
    }
    core.run(m, d, step, next_decision, rhythm, control);
  }
  double* last = block.next();
  recorder.before_step(last, steps, m, d, false, d->ncon);
  // Before the forward pass, which would overwrite the warmstart the next step needs.
  result.final_state = get_state(m, d);
  // MuJoCo derives a state's quantities (and its energy) during a step; the
  // final state has had none, so a forward pass (no time advances) does it.
  core.derive(m, d, steps);
  recorder.after_step(last, m, d);
  for (StepObserver* o : observers) o->at_end(m, d, last);
  result.final_row.assign(last, last + width);
  block.flush_to(rows);

  result.warnings = core.health().warnings();
  result.sim_time = d->time;
  return result;
}

}  // namespace simloop::detail
