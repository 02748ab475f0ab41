// What a scenario's run records, and the loop that only reads its schedule.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "simloop/control.hpp"
#include "simloop/run.hpp"
#include "simloop/scenario.hpp"

namespace simloop {

// The columns of a resolved scenario, laid out once, and how to fill a row.
//
// A row holds the state entering its step and the inputs written for that
// step, as in the chapter. Columns read straight from the state (joint
// positions and velocities) are taken before mj_step; quantities MuJoCo
// derives from that state (body poses and velocities, actuator forces,
// sensors, contacts) are taken right after it, when mj_step has computed them
// for exactly that state (read before it, they would lag by one step). The
// final row gets them from mj_forward.
//
// Columns, in order: step, time; `<actuator>_ctrl` (the ctrl MuJoCo applied,
// after ctrlrange clamping) for every controlled or recorded actuator;
// `<body>_fx _fy _fz _tx _ty _tz` (xfrc_applied, world frame) for every
// disturbed body; per recorded body `_x _y _z` (position, world, m), `_qw _qx
// _qy _qz` (orientation), `_vx _vy _vz` (linear velocity, world, m/s), `_wx _wy
// _wz` (angular velocity, world, rad/s); per recorded joint `_pos` and `_vel`
// (m and m/s for a slide, rad and rad/s for a hinge; `_pos0..` for the
// several numbers of ball and free joints); per recorded actuator `_force`
// (N or N m); per recorded sensor its value(s); `ncon` (contacts).
class Recorder {
 public:
  Recorder(const mjModel* m, const ResolvedScenario& scenario, const Schedule& schedule);

  [[nodiscard]] const std::vector<Column>& columns() const noexcept { return columns_; }
  [[nodiscard]] int width() const noexcept { return static_cast<int>(columns_.size()); }

  // Before mj_step: step, time, inputs (NaN in the final row) and the state.
  void before_step(double* row, std::int64_t step, const mjModel* m, const mjData* d, bool inputs) const noexcept;
  // After mj_step (or mj_forward): what MuJoCo derived from the row's state.
  void after_step(double* row, const mjModel* m, const mjData* d) const noexcept;

 private:
  struct Source {
    enum Kind { kCtrl, kXfrc, kBodyPose, kBodyVelocity, kQpos, kQvel, kActuatorForce, kSensor, kContacts } kind;
    int id = 0;      // actuator, body, or address into qpos/qvel/sensordata
    int count = 1;   // numbers it fills
    int column = 0;  // its first column
  };
  void add(Source::Kind kind, int id, int count, const std::vector<std::string>& names, const std::string& unit,
           bool integer = false, bool input = false);
  std::vector<Column> columns_;
  std::vector<Source> before_, after_;
  std::vector<double> ctrl_low_, ctrl_high_;  // per actuator; +-inf when not limited
};

// A scenario run's outcome: the schedule it followed (the drawn forces and
// the windows as they actually happened), the recorded rows, the warnings.
struct ScenarioRunResult {
  std::string name;          // the scenario's
  std::uint64_t seed = 0;
  std::string rng;           // the generator's name ("mt19937_64", "numpy")
  bool perturb = true;
  std::vector<std::string> disturbed_bodies;  // schedule.forces[i]'s body, by name
  std::vector<Column> columns;
  std::vector<double> final_row;  // the last row, whether kept or streamed
  std::vector<double> final_state;  // the full state at the end (state.hpp's layout)
  Trajectory trajectory;  // empty when the rows went to a RowSink
  std::int64_t rows = 0;
  Schedule schedule;
  std::vector<Warning> warnings;
  double timestep = 0.0;
  double sim_time = 0.0;
};

// A run's inputs of the caller's own, as mujoco.rollout takes them: read in
// place (nothing is copied), so they must outlive the run and not change
// during it. Either may be left null.
struct RunInputs {
  // steps x control_width doubles, row-major: row t is the whole ctrl vector
  // (one value per actuator, nu) written before step t. It replaces the
  // scenario's controls; its disturbances still apply. Values are written
  // as given (MuJoCo clamps them to ctrlrange when it applies them) and
  // must be finite.
  const double* controls = nullptr;
  std::int64_t control_steps = 0;
  std::int64_t control_width = 0;
  // state_size(m) doubles in state.hpp's layout: the run starts from this
  // state (time included) instead of the scene's reset pose.
  const double* initial_state = nullptr;
  std::size_t state_size = 0;
};

// Throws InvalidArgument naming `controls` or `initial_state` unless
// `inputs` fit a run of `steps` steps of `m`: control_steps == steps,
// control_width == nu, state_size == state_size(m), every value finite.
void check_inputs(const mjModel* m, const RunInputs& inputs, std::int64_t steps);

// The loop: reset (or set the initial state), mj_forward, then for each step
// write the schedule's inputs (ctrl changes, or the caller's controls;
// forces, explicit zeros when a window closes), record, mj_step. `m` and `d`
// must belong together; `d` is reset first.
[[nodiscard]] ScenarioRunResult run_schedule(const mjModel* m, mjData* d, const ResolvedScenario& scenario,
                                             const Schedule& schedule, std::int64_t record_every,
                                             RowSink* sink = nullptr, RunControl* control = nullptr,
                                             const RunInputs& inputs = {});

}  // namespace simloop
