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
// energy audit, the chapter's drift) the observers'. The stepping itself
// (the reset, the MuJoCo error guard, the watch for warnings and
// divergence, a decision's observation) is the core's, which Sim and
// Episodes step through too (stepper.hpp); between chunks of steps the rows
// go to the sink and the control may stop the run.
#pragma once

#include <mujoco/mujoco.h>

#include <cstdint>
#include <vector>

#include "simloop/control.hpp"
#include "simloop/recorder.hpp"
#include "simloop/rows.hpp"
#include "simloop/scenario.hpp"

namespace simloop::detail {

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

// What the loop leaves besides the rows it gave the sink.
struct LoopResult {
  std::int64_t rows = 0;            // rows recorded, kept or streamed
  std::vector<double> final_row;    // the last row
  std::vector<double> final_state;  // the full state at the end (state.hpp's layout)
  std::vector<Warning> warnings;    // MuJoCo's, then simloop's divergence
  double timestep = 0.0;
  double sim_time = 0.0;
};

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
