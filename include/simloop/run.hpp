// The chapter's run: load, step, shove mid-run, read out what happened.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "simloop/chapter_scene.hpp"
#include "simloop/control.hpp"
#include "simloop/model.hpp"
#include "simloop/rows.hpp"
#include "simloop/run_record.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/shove.hpp"

namespace simloop {

// --smoke: a short, fixed run so CI can compare two runs byte for byte.
inline constexpr std::int64_t kSmokeSteps = 300;

struct RunConfig {
  std::uint64_t seed = 0;                // seeds the shove, and nothing else
  std::int64_t steps = 2000;             // ignored when smoke is set
  double timestep = 0.002;               // written into (a copy of) the model
  bool perturb = true;                   // false: no shove (the baseline)
  bool smoke = false;                    // fixed kSmokeSteps steps
  std::int64_t record_every = 1;         // trajectory row every K steps (+ the final state)
  bool audit_energy = false;             // account for every joule: adds the energy columns
  ShoveRng rng = ShoveRng::kMt19937_64;  // the generator that draws the shove from the seed

  [[nodiscard]] std::int64_t num_steps() const noexcept { return smoke ? kSmokeSteps : steps; }
};

// Throws InvalidArgument naming the field and value: timestep not finite and
// positive, steps or record_every outside 1 .. kMaxSteps / kMaxRecordEvery.
// (Whether the trajectory fits in memory is a separate question: a run that
// streams its rows to a RowSink keeps none of them.)
void validate(const RunConfig& config);

// The rows a run keeps in memory without a RowSink: what check_kept_rows
// (rows.hpp) weighs before run() starts (the config must be valid).
[[nodiscard]] KeptRows kept_rows(const RunConfig& config) noexcept;

// metrics.json: the chapter's keys, floats already rounded to 6 decimals.
struct Metrics {
  std::int64_t steps = 0;
  std::uint64_t seed = 0;
  bool perturb = true;
  std::array<double, 3> box_final_pos{};
  double box_final_speed = 0.0;
  double pusher_final_x = 0.0;
  double lateral_drift = 0.0;    // |final y - y when the shove started|
  bool shove_moved_box = false;  // unrounded lateral_drift > 0.01 m
};

// The chapter's trajectory columns, in order (chapter_columns() describes
// them as Columns).
struct ChapterColumns {
  enum : int {
    kStep,
    kTime,
    kCtrl,
    kShoveX,
    kShoveY,
    kShoveZ,
    kBoxX,
    kBoxY,
    kBoxZ,
    kBoxQw,
    kBoxQx,
    kBoxQy,
    kBoxQz,
    kBoxVx,
    kBoxVy,
    kBoxVz,
    kBoxWx,
    kBoxWy,
    kBoxWz,
    kPusherX,
    kPusherVx,
    kNcon,
    kNumBaseColumns,
    // The energy audit's columns (RunConfig::audit_energy), all in joules.
    // energy: kinetic + potential of the row's state. work_*: work done on
    // the system by each kind of force from t = 0 up to the row's state
    // (cumulative, so any two rows give the work between them). *_positive:
    // only the steps where constraints (contacts) did positive work.
    // energy_unexplained: (energy - energy at t = 0) - all the work above.
    kEnergy = kNumBaseColumns,
    kWorkActuator,
    kWorkShove,
    kWorkPassive,
    kWorkConstraint,
    kWorkConstraintPositive,
    kEnergyUnexplained,
    kNumColumns
  };
  static constexpr std::array<std::string_view, kNumColumns> kNames = {"step",
                                                                       "time",
                                                                       "ctrl",
                                                                       "shove_x",
                                                                       "shove_y",
                                                                       "shove_z",
                                                                       "box_x",
                                                                       "box_y",
                                                                       "box_z",
                                                                       "box_qw",
                                                                       "box_qx",
                                                                       "box_qy",
                                                                       "box_qz",
                                                                       "box_vx",
                                                                       "box_vy",
                                                                       "box_vz",
                                                                       "box_wx",
                                                                       "box_wy",
                                                                       "box_wz",
                                                                       "pusher_x",
                                                                       "pusher_vx",
                                                                       "ncon",
                                                                       "energy",
                                                                       "work_actuator",
                                                                       "work_shove",
                                                                       "work_passive",
                                                                       "work_constraint",
                                                                       "work_constraint_positive",
                                                                       "energy_unexplained"};
};

// The chapter's first `count` columns (ChapterColumns::kNames).
[[nodiscard]] std::vector<Column> chapter_columns(int count);

// The chapter's run: the record any run leaves (its name the chapter
// scenario's, its columns ChapterColumns, its schedule the motor's 1.0 and
// the shove's window), with the chapter's report on top.
struct RunResult : RunRecord {
  RunConfig config;
  Metrics metrics;
  Metrics unrounded_metrics;  // the same, floats as computed (tables; metrics.json rounds)
  Shove shove;                // the shove drawn for this run (applied only if perturb)
};

// The chapter is a scenario: Scenario::chapter() fitted to `model` (any
// scene with the chapter's layout, chapter_layout): full throttle on
// actuator 0, the shove on the body "box", and recorded, the box, actuator
// 0's joint and the chapter's ncon.
[[nodiscard]] Scenario chapter_scenario(const Model& model);

// What one chapter run asks of that scenario (its seed, generator,
// timestep, steps, shove or none, rows, energy audit).
[[nodiscard]] ScenarioConfig scenario_config(const RunConfig& config);

// Runs chapter_scenario(model) with scenario_config(config) as run_scenario
// runs it, seen through the chapter's view: the chapter's columns in its
// order (the ctrl written, the shove's force, zeros when there is none),
// its metrics and its report. In a fresh mjData.
[[nodiscard]] RunResult run(const Model& model, const RunConfig& config);

// The same, reusing `workspace` (reset first), which must fit the model:
// batches keep one Data per worker. The result does not depend on what the
// workspace held before. With a `sink`, the rows go there and
// result.trajectory stays empty. With a `control`, the run can be stopped
// (Interrupted) and watched.
[[nodiscard]] RunResult run(const Model& model, const RunConfig& config, Data& workspace, RowSink* sink = nullptr,
                            RunControl* control = nullptr);

}  // namespace simloop
