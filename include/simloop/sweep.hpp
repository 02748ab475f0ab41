// Break It, measured: the baseline run (no shove) at many timesteps over the
// same span of simulated time, and where it stops being stable.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "simloop/model.hpp"
#include "simloop/run.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"

namespace simloop {

// The stability criterion, stated once. A timestep is stable when, over the
// sweep's span, (1) the box's centre never rises more than kStableHop above
// its resting height (10% of its half-height: the push itself lifts it 1.7 to
// 3.5 mm at every default timestep up to 0.004 s, through contact softness;
// from 0.005 s the hop passes 5 mm, 46 mm at 0.04 s), (2) it does not end more
// than kStableSink below its resting height (from 0.08 s it sinks into the
// floor, and through it from 0.3 s), and (3) no warning was raised
// (MuJoCo's, or simloop_DIVERGED). Sideways drift does not mark the edge: the box drifts a few
// centimetres at every timestep on MuJoCo 2.2.2.
inline constexpr double kStableHop = 0.005;       // m
inline constexpr double kStableSink = 0.001;      // m
inline constexpr double kBoxRestZ = 0.05;         // m, the chapter's box at rest
inline constexpr double kBreakItTimestep = 0.05;  // s, Break It's: 25 times the chapter's

// A point of the chapter's sweep: its scenario's point (ScenarioSweepPoint)
// as the chapter reads it, judged by the criterion above.
struct SweepPoint {
  double timestep = 0.0;
  std::int64_t steps = 0;
  double peak_box_z = 0.0;     // highest the box's centre got, m
  double max_abs_box_y = 0.0;  // furthest sideways, m
  double final_box_x = 0.0, final_box_y = 0.0, final_box_z = 0.0;
  double final_pusher_x = 0.0;
  std::int64_t warnings = 0;  // warnings raised, all kinds: MuJoCo's and simloop_DIVERGED
  EnergyTotals energy;        // the energy audit over the run
  bool stable = false;
};

struct SweepResult {
  double duration = 0.0;           // sim seconds each run covers
  std::vector<SweepPoint> points;  // in ascending timestep order
  // The largest timestep below which every swept timestep is stable; -1 if
  // even the finest is not.
  int edge_index = -1;
};

// A sweep point runs round(duration / timestep) steps, which must lie in
// kMinSweepSteps .. kMaxSteps: fewer steps cannot show the box settle or hop
// (the default grid's coarsest point, 1 s over 4 s, has 4), more cannot be
// counted. sweep_steps returns that count or throws InvalidArgument naming
// the duration, the timestep and the steps they make.
inline constexpr std::int64_t kMinSweepSteps = 4;
[[nodiscard]] std::int64_t sweep_steps(double duration, double timestep);

// `count` timesteps from `from` to `to`, evenly spaced in log scale.
[[nodiscard]] std::vector<double> log_spaced(double from, double to, int count);

// The default sweep: 25 round timesteps, 1, 2, 3, 4, 5, 6 and 8 times a power
// of ten, from 0.0005 s to 1 s (each exactly the double its decimal names).
// Seven per decade, not 1-2-5: the edge lies between 0.002 and 0.005 s, and
// 1-2-5 would have nothing there to find it with.
[[nodiscard]] std::vector<double> default_sweep_timesteps();

// The chapter's sweep: sweep_scenario on chapter_scenario(model), the
// baseline (no shove) with the energy audit on, seen as the chapter sees it:
// the box's figures, the pusher's final position (actuator 0's joint, from
// each run's final row), every warning as one count, then judged
// (judge_sweep). Throws InvalidArgument naming a bad timestep, duration or
// thread count, before any run starts. With a `control`, it can be stopped
// (Interrupted) and watched.
[[nodiscard]] SweepResult sweep(const Model& model, std::vector<double> timesteps, double duration = 4.0,
                                int threads = 0, RunControl* control = nullptr);

// Applies the criterion above to each point (stable) and finds the edge:
// what sweep() does with its points once they are run. Points run elsewhere
// (on a cluster's workers, in chunks of timesteps) are judged the same way.
void judge_sweep(SweepResult& result);

// One sweep from `parts` run apart (a cluster's chunks of timesteps), in
// order: their points joined, then judged (judge_sweep). Throws
// InvalidArgument if there are no parts, their durations differ, or the
// joined timesteps do not ascend.
[[nodiscard]] SweepResult join_sweeps(const std::vector<SweepResult>& parts);

// sweep.csv: a header and one line per timestep.
[[nodiscard]] std::string sweep_csv(const SweepResult& result);

// A table for people, then the edge and the criterion.
[[nodiscard]] std::string sweep_summary(const SweepResult& result);

// ---------------------------------------------------------------------------
// A scenario, swept: any scene at many timesteps over the same span of
// simulated time. A scene has no resting box to measure a hop against, so
// the criterion is general: the finest timestep is the reference, and a
// timestep "blew up" when
//   (1) a warning was raised while it ran (MuJoCo's, or simloop_DIVERGED), or
//   (2) a recorded body's final position is not finite, or lies further than
//       kScenarioSweepTolerance times the scene's size from where the
//       reference run left it. The scene's size is MuJoCo's own measure of
//       it, mjModel::stat.extent (the span of its bodies and geoms), so the
//       tolerance scales with the scene: 10% of it (5.9 cm for the PushT
//       test scene, 18.7 cm for the walker). Contact-rich scenes drift apart
//       a few per cent of their size between sound timesteps (the PushT
//       block ends 0.7 to 3.6 cm from the reference at 0.0006 to 0.004 s);
//       a tenth of the scene is past that noise and well short of the metres
//       a blow-up throws a body.
// The reference cannot blow up by (2); it can by (1). The largest speed any
// recorded body reached is reported beside, as a sign to read, not a rule.
inline constexpr double kScenarioSweepTolerance = 0.10;

struct ScenarioSweepPoint {
  double timestep = 0.0;
  std::int64_t steps = 0;
  std::int64_t mujoco_warnings = 0;                    // MuJoCo's warnings raised, all kinds
  std::int64_t diverged = 0;                           // simloop_DIVERGED raised
  double peak_speed = 0.0;                             // largest linear speed of any recorded body over the run, m/s
  std::vector<std::array<double, 3>> final_positions;  // per recorded body (ScenarioSweepResult::bodies), m
  std::vector<double> offsets;                         // each one's distance from the reference's final position, m
  double max_offset = 0.0;                             // the largest of them (NaN if any is not finite)
  bool blew_up = false;
  // What other criteria read (the chapter's hop): per recorded body, the
  // highest its centre got and the furthest from y = 0, m; the energy
  // audit's totals (zeros unless config.audit_energy); the run's final row.
  std::vector<double> peak_z, max_abs_y;
  EnergyTotals energy;
  std::vector<double> final_row;  // in ScenarioSweepResult::columns
};

struct ScenarioSweepResult {
  std::string name;                        // the scenario's
  double duration = 0.0;                   // sim seconds each run covers
  std::vector<std::string> bodies;         // the recorded bodies, in the columns' order
  std::vector<Column> columns;             // the runs' columns
  double scene_size = 0.0;                 // mjModel::stat.extent, m
  double tolerance = 0.0;                  // kScenarioSweepTolerance * scene_size, m
  std::vector<ScenarioSweepPoint> points;  // ascending timesteps; points[0] is the reference
  // The largest timestep below which no swept timestep blew up; -1 if even
  // the finest did.
  int edge_index = -1;
};

// The scenario's own span of simulated time: its duration in seconds, or
// its steps at its timestep (the scenario's, else the scene's).
[[nodiscard]] double scenario_duration(const Model& scene, const Scenario& scenario);

// The default grid (default_sweep_timesteps) without the timesteps that
// would give a run of `duration` fewer than kMinSweepSteps steps.
[[nodiscard]] std::vector<double> default_scenario_sweep_timesteps(double duration);

// Runs `scenario` at every timestep (sorted, duplicates dropped) for
// sweep_steps(duration, timestep) steps each, with `config`'s seed, rng and
// perturb (its timestep, steps and record_every are the sweep's: every step
// is read). The scene is compiled once per timestep and each worker steps
// its own Data (run_scenario_batch), so each point is bitwise what
// run_scenario with that timestep and those steps gives. Rows are reduced as
// they come: a sweep keeps no trajectories. Throws InvalidArgument naming a
// bad timestep, duration, thread count or scenario name before any run.
[[nodiscard]] ScenarioSweepResult sweep_scenario(const Model& scene, const Scenario& scenario,
                                                 std::vector<double> timesteps, double duration,
                                                 const ScenarioConfig& config = {}, int threads = 0,
                                                 RunControl* control = nullptr);

// sweep.csv for a scenario: timestep, steps, mujoco_warnings, diverged,
// peak_speed, then per recorded body <body>_final_x, _final_y, _final_z and
// <body>_offset, then max_offset, tolerance (the same on every line) and
// blew_up (1 or 0).
[[nodiscard]] std::string sweep_csv(const ScenarioSweepResult& result);

// A table for people, then the edge and the rule.
[[nodiscard]] std::string sweep_summary(const ScenarioSweepResult& result);

}  // namespace simloop
