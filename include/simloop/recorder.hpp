// What a scenario's run records, and the loop that only reads its schedule.
#pragma once

#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "simloop/control.hpp"
#include "simloop/fields.hpp"
#include "simloop/rows.hpp"
#include "simloop/run_record.hpp"
#include "simloop/scenario.hpp"

namespace simloop {

// The range MuJoCo clamps each actuator's ctrl to: its ctrlrange when
// ctrllimited (and clamping is not disabled), else -inf..inf.
struct CtrlRange {
  std::vector<double> low, high;  // per actuator
};
[[nodiscard]] CtrlRange ctrl_range(const mjModel* m);

// The columns of a recorded joint's position: "<joint>_pos", or _pos0 ..
// for the 4 or 7 numbers of a ball or free joint.
[[nodiscard]] std::vector<std::string> joint_position_columns(const mjModel* m, int joint);

// What a run's rows hold: their columns, and how to fill one. The loop calls
// before_step when it records a row, after_step once that step is taken.
class RowRecorder {
 public:
  virtual ~RowRecorder() = default;
  [[nodiscard]] virtual const std::vector<Column>& columns() const noexcept = 0;
  [[nodiscard]] int width() const noexcept { return static_cast<int>(columns().size()); }
  // Before mj_step: step, time, the inputs just written (NaN in the final
  // row, which has no step after it) and the state entering the step.
  // ncon: the contacts MuJoCo had found when the step began (its last
  // collision pass: the previous step's, row 0's the first mj_forward's),
  // which d no longer holds once a decision's observation has derived the
  // state again (loop.hpp's DecisionStep::entering_ncon).
  virtual void before_step(double* row, std::int64_t step, const mjModel* m, const mjData* d, bool inputs,
                           int ncon) const noexcept = 0;
  // After mj_step (the final row: after mj_forward): what MuJoCo derived
  // from the row's state.
  // It may fill what MuJoCo computes only on request (mj_rnePostConstraint's
  // cfrc_ext, say) when a column reads it.
  virtual void after_step(double* row, const mjModel* m, mjData* d) const noexcept = 0;
  // Whether after_step reads anything of MuJoCo's acceleration stage but
  // the actuator forces (an acceleration-stage sensor, say): a decision's
  // observation then takes a whole forward pass (stepper.hpp's Stepper::observe).
  [[nodiscard]] virtual bool reads_acceleration_stage() const noexcept { return true; }
};

// The columns of a resolved scenario, laid out once, and how to fill a row.
//
// A row holds the state entering its step and the inputs written for that
// step, as in the chapter. Columns read straight from the state (joint
// positions and velocities, a free body's pose and velocity: its joint's)
// are taken before mj_step; quantities MuJoCo derives from that state (other
// bodies' poses and velocities, actuator forces, sensors, contacts) are taken
// right after it, when mj_step has computed them for exactly that state (read
// before it, they would lag by one step). The final row gets them from
// mj_forward. Under RK4, whose later stages leave them for another state, a
// recorded row derives them before its step (a forward pass more per
// recorded row, the run's bits unchanged).
//
// A name means one quantity wherever it appears, the chapter's trajectory
// included (docs/cli.md's table of columns). Columns, in order: step, time;
// `<actuator>_ctrl` (the ctrl MuJoCo applied, after ctrlrange clamping) for
// every controlled or recorded actuator; `<body>_fx _fy _fz _tx _ty _tz`
// (xfrc_applied, world frame) for every disturbed body; per recorded body
// `_x _y _z` (its frame's origin, world, m), `_qw _qx _qy _qz` (orientation),
// `_vx _vy _vz` (the origin's linear velocity, world frame, m/s), `_wx _wy
// _wz` (angular velocity in the body's own frame, rad/s): for a body on a
// free joint of the world these are its joint's qpos and qvel, bit for bit
// the chapter's box; per recorded joint `_pos` and `_vel` (m and m/s for a
// slide, rad and rad/s for a hinge; `_pos0..` for the several numbers of ball
// and free joints); per recorded actuator `_force` (N or N m); per recorded
// sensor its value(s); per recorded tendon `_length` and `_vel` (m and m/s,
// or rad for a fixed tendon of hinges); `contacts` (the contacts of the row's
// state); `ncon` (the chapter's: the contacts found when the step began, the
// row before's state's); with `energy`, the energy audit's columns last
// (kEnergyColumns: the audit fills them, as the run goes).
inline constexpr int kEnergyColumns = 7;
class Recorder final : public RowRecorder {
 public:
  Recorder(const mjModel* m, const ResolvedScenario& scenario, const Schedule& schedule, bool energy = false);

  [[nodiscard]] const std::vector<Column>& columns() const noexcept override { return columns_; }
  void before_step(double* row, std::int64_t step, const mjModel* m, const mjData* d, bool inputs,
                   int ncon) const noexcept override;
  void after_step(double* row, const mjModel* m, mjData* d) const noexcept override;
  [[nodiscard]] bool reads_acceleration_stage() const noexcept override { return reads_acceleration_stage_; }
  // The first of the energy audit's columns, or -1 without them.
  [[nodiscard]] int energy_column() const noexcept { return energy_column_; }
  // With `on`, the data columns ([record] data) are not read for the row's
  // state but by read_data, where Gymnasium's MujocoEnv reads mjData: as
  // the last physics step left it (derived for the state entering that
  // step), cacc, cfrc_int and cfrc_ext by mj_rnePostConstraint after it;
  // after a reset, as its mj_forward left them (those three as the reset
  // did: zero). after_step then leaves those columns alone. (Episodes use
  // it; a run's rows keep the row's state.)
  void read_data_at_step(bool on) noexcept { data_at_step_ = on; }
  [[nodiscard]] bool data_at_step() const noexcept { return data_at_step_; }
  // The data columns of `row` from d as it is; `stepped`: d was left by a
  // physics step (not a reset). Inside MuJoCo's error guard.
  void read_data(double* row, const mjModel* m, mjData* d, bool stepped) const noexcept;

 private:
  struct Source {
    enum Kind {
      kCtrl,
      kXfrc,
      kBodyPose,
      kBodyVelocity,
      kQpos,
      kQvel,
      kActuatorForce,
      kSensor,
      kTendon,
      kData,
      kContactForce,
      kContacts,
      kNcon
    } kind;
    int id = 0;      // actuator, body, or address into qpos/qvel/sensordata
    int count = 1;   // numbers it fills
    int column = 0;  // its first column
  };
  // units: one per column, or one for them all.
  void add(Source::Kind kind, int id, int count, const std::vector<std::string>& names,
           const std::vector<std::string>& units, bool integer = false, bool input = false,
           const std::string& body = "");
  std::vector<Column> columns_;
  std::vector<Source> before_, after_;
  std::vector<std::pair<DataNumbers, long long>> data_;       // kData's id: an mjData array and its first value
  std::vector<ResolvedScenario::ContactPair> contact_pairs_;  // kContactForce's id: its pair
  std::vector<std::string> fills_;  // a recorded array per MuJoCo call that fills it (fill_derived)
  CtrlRange ctrl_range_;
  bool reads_acceleration_stage_ = false;  // an acceleration-stage sensor is recorded
  bool data_at_step_ = false;
  int energy_column_ = -1;
};

// The schedule's inputs as the loop writes them, step by step: at each step,
// the ctrl changes and the forces that start or stop there (the sum of the
// windows open on a body, an explicit zero when the last one closes;
// xfrc_applied and ctrl persist in MuJoCo until overwritten). Steps are taken
// in order from 0; writing the same step twice writes it once. Shared by run_schedule and Episodes (episode.hpp).
class ScheduledInputs {
 public:
  // controls = false: the schedule's ctrl changes are not written (a policy
  // sets ctrl instead); its forces still are.
  explicit ScheduledInputs(const Schedule& schedule, bool controls = true);

  void write(std::int64_t step, mjData* d) noexcept {
    for (; next_control_ < controls_.size() && controls_[next_control_].step == step; ++next_control_) {
      d->ctrl[controls_[next_control_].actuator] = controls_[next_control_].value;
    }
    for (; next_force_ < forces_.size() && forces_[next_force_].step == step; ++next_force_) {
      std::copy(forces_[next_force_].wrench.begin(), forces_[next_force_].wrench.end(),
                d->xfrc_applied + 6 * forces_[next_force_].body);
    }
  }

 private:
  struct ForceChange {  // from `step` on, xfrc_applied of `body` holds `wrench`
    std::int64_t step;
    int body;
    std::array<double, 6> wrench;
  };
  std::vector<Schedule::ControlChange> controls_;
  std::vector<ForceChange> forces_;
  std::size_t next_control_ = 0, next_force_ = 0;
};

// A policy in the loop: every `every()` steps (a decision step: 0, K, 2K, ...)
// the loop hands it the observation and takes back the ctrl of every
// actuator, which MuJoCo then holds for the next K steps.
//
// The observation is the recorder's row for the state entering the decision
// step (Recorder's columns, step and time first), computed before the
// decision: deciding leaves the run's bits as they would be with the same
// ctrl written open-loop (Stepper::observe, stepper.hpp, derives it as the first
// half of the next mj_step, or by forward_keeping_state); its ctrl columns
// hold the ctrl in force until now (the previous decision's; 0 before the
// first), and so do what follows from ctrl (actuator forces, acceleration
// sensors); its force columns hold the disturbances scheduled for this step.
//
// Who wins: with a policy, ctrl is the policy's, on every actuator, from
// step 0 on; the scenario's controls are not written. Its disturbances
// apply as scheduled.
//
// decide() runs outside MuJoCo's error guard, on the thread stepping the
// run (any worker of a batch: it must be safe to call from several threads
// at once); it may throw, which stops the run and reaches the caller.
class Policy {
 public:
  // every: 1 to kMaxSteps (InvalidArgument otherwise).
  explicit Policy(std::int64_t every);
  virtual ~Policy() = default;
  [[nodiscard]] std::int64_t every() const noexcept { return every_; }
  // observation: `width` doubles (the recorder's row); ctrl: the nu doubles
  // MuJoCo will apply from this step on, holding the ctrl in force now. The
  // loop takes what ctrl holds after the call through check_ctrl.
  virtual void decide(std::int64_t step, const double* observation, int width, std::vector<double>& ctrl) = 0;
  // A decision's ctrl as the loop takes it: nu values, each finite
  // (InvalidArgument naming the decision step otherwise).
  static void check_ctrl(std::int64_t step, const std::vector<double>& ctrl, int nu);

 private:
  std::int64_t every_;
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
  // Decides ctrl every policy->every() steps (see Policy); not with controls.
  Policy* policy = nullptr;

  // A run's inputs that are only a policy's decisions.
  [[nodiscard]] static RunInputs deciding(Policy& policy) noexcept {
    RunInputs inputs;
    inputs.policy = &policy;
    return inputs;
  }
};

// A caller's whole array, as numpy holds one: C-contiguous doubles and
// their shape.
struct InputArray {
  const double* data = nullptr;
  std::vector<std::int64_t> shape;
};

// Each run's inputs, read in place from whole arrays: controls shaped
// (runs, steps, nu) give run i its own slice and (steps, nu) every run the
// same; initial_state (runs, state_size) or (state_size,) likewise. With
// `batch` false (one run) only the shapes without runs are taken. Throws
// InvalidArgument naming the array and its shape otherwise; check_inputs
// then checks the sizes against the run.
[[nodiscard]] std::vector<RunInputs> split_inputs(std::size_t runs, bool batch,
                                                  const std::optional<InputArray>& controls,
                                                  const std::optional<InputArray>& initial_state);

// Throws InvalidArgument naming `controls` or `initial_state` unless
// `inputs` fit a run of `steps` steps of `m`: control_steps == steps,
// control_width == nu, state_size == state_size(m), every value finite, and
// not both controls and a policy.
void check_inputs(const mjModel* m, const RunInputs& inputs, std::int64_t steps);

// The loop: reset (or set the initial state), mj_forward, then for each step
// write the schedule's inputs (ctrl changes, or the caller's controls;
// forces, explicit zeros when a window closes), record, mj_step. `m` and `d`
// must belong together; `d` is reset first. With a policy in `inputs`, it
// also decides ctrl every policy->every() steps (see Policy): chunks of
// steps then end at decision steps, where the loop leaves MuJoCo's error
// guard to call it. Without one the steps run exactly as before (one more
// comparison per chunk of RunControl::kChunkSteps).
[[nodiscard]] RunRecord run_schedule(const mjModel* m, mjData* d, const ResolvedScenario& scenario,
                                     const Schedule& schedule, std::int64_t record_every, RowSink* sink = nullptr,
                                     RunControl* control = nullptr, const RunInputs& inputs = {});

}  // namespace simloop
