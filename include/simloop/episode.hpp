// Episodes of a scenario stepped from outside, one decision at a time: what a
// Gymnasium environment (one episode) and a vector environment (many, over
// one compiled model, each with its own Data) need.
//
// Each episode is a run of the scenario driven by decisions: reset draws its
// schedule from a seed (the disturbances; its controls give way to the
// actions, as with a Policy in run_schedule), and each step writes an action
// into ctrl and takes `every` physics steps. An episode stepped with the
// actions a Policy would have returned follows the bits of run_schedule with
// that policy: the same inputs, the same observations (the recorder's row
// for the state entering the next decision, derived as the first half of
// the next step: stepper.hpp's Stepper::observe).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "simloop/control.hpp"
#include "simloop/fields.hpp"
#include "simloop/model.hpp"
#include "simloop/recorder.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"

namespace simloop {

class Episodes {
 public:
  // `count` episodes of `scenario` on `scene` (as load_scene made it).
  // config: rng, timestep, steps (the episode's length) and perturb as for
  // run_scenario; its seed and record_every play no part (reset takes the
  // seed; nothing is recorded). Names are resolved here (InvalidArgument
  // listing what the scene has). No episode has started: reset each first.
  // read_state: something reads the episodes' whole state between steps
  // (a hook's data_field): each observation then takes a whole forward pass
  // (Stepper::observe), so every array is the observed state's, at the
  // cost of one forward pass a decision; the observations' bits are the same.
  Episodes(const Model& scene, const Scenario& scenario, const ScenarioConfig& config, std::size_t count,
           bool read_state = false);
  ~Episodes();
  Episodes(const Episodes&) = delete;
  Episodes& operator=(const Episodes&) = delete;

  [[nodiscard]] std::size_t count() const noexcept;
  [[nodiscard]] int nu() const noexcept;
  // The observation's width and columns: the recorder's (step and time first).
  [[nodiscard]] int width() const noexcept;
  [[nodiscard]] const std::vector<Column>& columns() const noexcept;
  // The length of an episode, in physics steps.
  [[nodiscard]] std::int64_t steps() const noexcept;
  // The model the episodes step (the scene at the run's timestep); an
  // episode started with scene parameters steps its own copy (model(i)).
  [[nodiscard]] const Model& model() const noexcept;
  // The scenario as configured: its [reset] is what reset options start from (reset_over).
  [[nodiscard]] const Scenario& scenario() const noexcept;
  [[nodiscard]] const Model& model(std::size_t i) const;
  // Episode i's state, as its last reset or step left it: what MuJoCo derives
  // from its positions and velocities is current (what a Renderer draws);
  // the acceleration stage may be the last physics step's.
  [[nodiscard]] const mjData* data(std::size_t i) const;
  // mjData's array `name` of episode i (fields.hpp's data_field), filled
  // first if MuJoCo fills it only on request (fill_derived): with
  // read_state, every array is the state of the episode's last observation.
  [[nodiscard]] FieldView data_field(std::size_t i, std::string_view name);

  // Starts episode i afresh (t = 0, the model's initial state, ctrl 0) with
  // its disturbances drawn from `seed`, then its start (the scenario's
  // ResetSpec, or `reset` for this episode instead when given (reset_over: the
  // scenario's with the keys the options name replaced): its state,
  // noise and scene parameters, drawn from the same seed after the
  // disturbances), and writes its first observation into
  // observation[0 .. width()). A bad `reset` throws InvalidArgument
  // (check_reset) and leaves the episode as it was.
  void reset(std::size_t i, std::uint64_t seed, double* observation, const ResetSpec* reset = nullptr);

  // reset in two calls, around a caller's hook that shapes the start (an
  // env's on_reset): stage_reset does reset's work up to the start's state
  // (checks, draws, scene parameters, keyframe, noise, goals) on a second
  // Data kept for episode i, leaving the episode itself as it was;
  // staged_field gives that start's mjData arrays to write (qpos, qvel, ...)
  // and staged_model its model; commit_reset makes the start consistent
  // (quaternions unit, mj_forward), writes its first observation and swaps
  // it in as episode i. A stage never committed (the hook failed) changes
  // nothing; the next stage_reset replaces it. Without a stage, staged_*
  // and commit_reset throw InvalidArgument.
  void stage_reset(std::size_t i, std::uint64_t seed, const ResetSpec* reset = nullptr);
  [[nodiscard]] FieldView staged_field(std::size_t i, std::string_view name);
  [[nodiscard]] const Model& staged_model(std::size_t i) const;
  void commit_reset(std::size_t i, double* observation);
  // What episode i's start drew (its scene parameters, goals, keyframe).
  [[nodiscard]] const Schedule::Start& start(std::size_t i) const;

  // For each episode i with active[i] (all when `active` is null): writes
  // actions[i*nu .. i*nu+nu) into its ctrl and takes `every` physics steps
  // (fewer if the episode reaches its length, or ends on divergence first),
  // then writes its observation into observations[i*width ..) and its flags:
  // terminated[i] when it diverged (simloop_DIVERGED) or MuJoCo found a bad
  // position, velocity or acceleration and reset the state
  // (mjWARN_BADQPOS, BADQVEL, BADQACC); truncated[i] when it reached its
  // length without that. Inactive episodes' rows and flags are left alone.
  // Episodes step in parallel on `threads` workers (0: one per core; the
  // batches' pool), each independent of the others: the same bits whatever
  // the thread count. Checked before any step: actions holds action_count
  // = count() x nu() values and active (if given) active_count = count()
  // flags, every active episode was reset and has not ended, every action is
  // finite, every is from 1 to kMaxSteps (InvalidArgument naming the episode
  // or argument).
  void step(const double* actions, std::size_t action_count, std::int64_t every, const std::uint8_t* active,
            std::size_t active_count, double* observations, std::uint8_t* terminated, std::uint8_t* truncated,
            int threads = 1, RunControl* control = nullptr);

  // Observations read [record] data where Gymnasium's MujocoEnv reads
  // mjData, as the last physics step (or the reset) left it
  // (Recorder::read_data_at_step), not for the observed state.
  void read_data_at_step(bool on) noexcept;

  // Episode i's physics steps taken since its reset, its sim time, and the
  // warnings it raised (MuJoCo's and simloop_DIVERGED).
  [[nodiscard]] std::int64_t steps_taken(std::size_t i) const;
  [[nodiscard]] double time(std::size_t i) const;
  [[nodiscard]] std::vector<Warning> warnings(std::size_t i) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace simloop
