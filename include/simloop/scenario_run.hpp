// Running a scenario: its scene compiled once, then any number of runs, each
// scenario -> schedule (drawn from the seed) -> the loop -> what was asked
// recorded, and what the run leaves behind (metrics.json, the summary).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "simloop/control.hpp"
#include "simloop/model.hpp"
#include "simloop/recorder.hpp"
#include "simloop/scenario.hpp"
#include "simloop/shove.hpp"

namespace simloop {

// What one run of a scenario varies; the scenario fixes the rest.
struct ScenarioConfig {
  std::uint64_t seed = 0;                // seeds the random disturbances, and nothing else
  ShoveRng rng = ShoveRng::kMt19937_64;  // the generator that draws them
  std::optional<double> timestep;        // instead of the scenario's (or the scene's own)
  std::optional<std::int64_t> steps;     // instead of the scenario's length
  bool perturb = true;                   // false: no disturbances (the baseline)
  std::int64_t record_every = 1;         // a row every K steps, and the final state
  // Account for every joule: the energy audit's columns after the others
  // (energy, work_actuator, work_shove, work_passive, work_constraint,
  // work_constraint_positive, energy_unexplained; docs/cli.md) and its
  // totals in RunRecord::energy.
  bool audit_energy = false;
};

// The scene a scenario names, compiled: its MJCF file, or the chapter's
// embedded scene when it names none.
[[nodiscard]] Model load_scene(const Scenario& scenario);

// Runs `scenario` on `scene` (as load_scene made it, or any Model of the
// same scene): the timestep is config's, else the scenario's, else the
// scene's own. Names are resolved first (InvalidArgument listing what the
// scene has), then the schedule is drawn, then the loop runs in `workspace`
// (a fresh Data if null). Same scenario, scene, config: the same bits.
// With `inputs` (recorder.hpp's RunInputs), the run follows the caller's
// controls, or a policy's decisions (Policy in recorder.hpp), instead of the
// scenario's controls, and starts from the caller's state; all checked
// first (InvalidArgument naming them).
[[nodiscard]] RunRecord run_scenario(const Model& scene, const Scenario& scenario, const ScenarioConfig& config,
                                     Data* workspace = nullptr, RowSink* sink = nullptr, RunControl* control = nullptr,
                                     const RunInputs& inputs = {});

// Everything run_scenario() checks before its first step (the names, the
// length, the recorded columns), without running: throws InvalidArgument as
// run_scenario() would. The commands call it before touching --out.
void check_scenario(const Model& scene, const Scenario& scenario, const ScenarioConfig& config);

// The names of the columns such a run records ("step" and "time" first: a
// policy's observation is a row of them), after check_scenario's checks.
[[nodiscard]] std::vector<std::string> scenario_columns(const Model& scene, const Scenario& scenario,
                                                        const ScenarioConfig& config);

// The timestep a run of `scenario` on `scene` with `config` steps at:
// config's, else the scenario's, else the scene's own.
[[nodiscard]] double run_timestep(const Model& scene, const Scenario& scenario, const ScenarioConfig& config);

// Runs `scenario` once per config over one scene, with `threads` workers (0:
// one per core), each stepping its own Data; the scene is compiled once per
// distinct timestep (and energy audit), before any worker starts, and
// shared read-only. Result i is bitwise identical to run_scenario(scene,
// scenario, configs[i]), whatever the thread count. Every run is checked
// before any starts (InvalidArgument naming its index: a bad timestep, an
// unknown name, steps or record_every out of range, or kept rows that
// together would not fit in memory). If runs fail, the failure of the lowest
// index is rethrown after all workers have stopped, no new run starts once
// one has failed, and the runs still going stop at their next chunk of
// steps. If threads cannot be created, fewer workers do the work (the
// results are the same). With a `control`, the batch can be stopped
// (Interrupted) and watched; its poll runs on the calling thread.
// inputs: empty, or one RunInputs per config (run i follows inputs[i]; runs
// may share the same arrays, and the same policy, whose decide() is then
// called from every worker thread and must allow that; each run's decisions
// depend only on its own observations, so results stay bitwise those of
// run_scenario whatever the thread count), checked with the rest before any
// run starts.
// keep_rows false: the runs keep no trajectory (each result still has its
// final_row, final_state, warnings and schedule, which is all the metrics
// need), so a batch's memory does not grow with its runs' lengths.
[[nodiscard]] std::vector<RunRecord> run_scenario_batch(const Model& scene, const Scenario& scenario,
                                                        const std::vector<ScenarioConfig>& configs, int threads = 0,
                                                        RunControl* control = nullptr,
                                                        const std::vector<RunInputs>& inputs = {},
                                                        bool keep_rows = true);

// The same, with run i's rows going to sinks[i] (one per config; null: kept
// in its result's trajectory; each used by one worker at a time): a sink
// that reduces rows as they come lets a batch of any length run in little
// memory (the scenario sweep does; keep_rows false above is DiscardRows).
[[nodiscard]] std::vector<RunRecord> run_scenario_batch(const Model& scene, const Scenario& scenario,
                                                        const std::vector<ScenarioConfig>& configs,
                                                        const std::vector<RowSink*>& sinks, int threads = 0,
                                                        RunControl* control = nullptr,
                                                        const std::vector<RunInputs>& inputs = {});

// ---------------------------------------------------------------------------
// Drawing a run (the rerun recording): every body that moves, not only the
// recorded ones, without changing what the run records.

// The bodies whose pose can change during a run (not welded to the world, or
// moved by mocap) and that have geoms to draw, by name ("body<id>" when
// unnamed, as the recorder and scene_geometry name them), in body order.
[[nodiscard]] std::vector<std::string> moving_bodies(const Model& scene);

// run_scenario with its rows going to `sink`, bitwise the rows run_scenario
// gives (the same columns: a recording changes nothing in trajectory.csv),
// and, at the same rows, the same values followed by the pose of every body
// in moving_bodies() (x y z, then qw qx qy qz: its frame in the world, read
// where the recorded bodies' poses are), then every joint's position in
// joint order (nq values: the row's qpos, from which a picture is drawn),
// going to `drawing`. It is one run: the recorder reads the extra bodies
// and joints too, and the rows are split. The
// result is labelled as run_scenario's, with the trajectory's columns.
[[nodiscard]] RunRecord run_scenario_drawn(const Model& scene, const Scenario& scenario, const ScenarioConfig& config,
                                           RowSink& sink, RowSink& drawing, RunControl* control = nullptr);

}  // namespace simloop
