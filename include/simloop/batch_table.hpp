// A batch's table: one row per run of a scenario, the numbers Python's
// BatchTable shows (python/simloop/tables.py), reduced from each run's
// record as the run ends. A batch that keeps only this holds a few hundred
// bytes per run, not the run's record (its columns, schedule and state).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "simloop/model.hpp"
#include "simloop/recorder.hpp"
#include "simloop/run_record.hpp"
#include "simloop/scenario_run.hpp"

namespace simloop {

// A column a run's row holds beyond the ones every row has: for each
// recorded body (by name) <body>_final_pos_x/y/z and <body>_final_speed,
// then for each disturbance disturbance<i>_fx..tz, _start_step and _steps,
// then what the start drew (scenario.hpp's drawn_columns: each scene
// parameter by tables.py's param_column name, each goal's goal_<body>_x/y/z).
struct TableColumn {
  std::string name;
  bool integer = false;  // a count of steps (held exactly as a double)
};

struct TableRow {
  std::string scenario, rng;
  std::uint64_t seed = 0;
  double timestep = 0.0;
  std::int64_t steps = 0;
  bool perturb = true;
  double sim_time = 0.0;
  std::size_t layout = 0;      // which of ScenarioTable::layouts `values` follows
  std::vector<double> values;  // one per column of that layout
  // Each warning's count, in the order of Python's WARNING_NAMES (MuJoCo's,
  // then simloop's): 0 where it was not raised, so tables of the same kind
  // of run have the same columns and join.
  std::vector<std::int64_t> warnings;
};

struct ScenarioTable {
  // The distinct column lists, in the order runs first had them (a batch of
  // one scenario has one).
  std::vector<std::vector<TableColumn>> layouts;
  std::vector<TableRow> rows;  // one per run, in run order
};

// |v| of a final velocity, as the run's report computes it; a square past
// double's range (a run that blew up) is scaled first, so the speed is
// finite whenever v is.
[[nodiscard]] double final_speed(double vx, double vy, double vz) noexcept;

// The table of these records (run order).
[[nodiscard]] ScenarioTable scenario_table(const std::vector<const RunRecord*>& records);

// run_scenario_batch(..., keep_rows = false) reduced to its table: the same
// runs, checks and bits, each run's record reduced to its row by the
// worker that ran it and then dropped, so the batch's memory does not grow
// with its runs beyond their rows.
[[nodiscard]] ScenarioTable run_scenario_table(const Model& scene, const Scenario& scenario,
                                               const std::vector<ScenarioConfig>& configs, int threads = 0,
                                               RunControl* control = nullptr,
                                               const std::vector<RunInputs>& inputs = {});

}  // namespace simloop
