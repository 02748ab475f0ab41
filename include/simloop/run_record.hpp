// The record every run leaves, whatever its scene: what it was asked (the
// scenario's name, seed, generator), the schedule it followed, its rows and
// what each column is, where it ended, and what MuJoCo warned of. The
// chapter's RunResult (run.hpp) is this record with the chapter's report on
// top; a batch is a list of them; metrics.json, the summary and the files
// (output.hpp) are made from it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "simloop/rows.hpp"
#include "simloop/scenario.hpp"

namespace simloop {

// The energy audit's totals over a whole run (ScenarioConfig::audit_energy,
// RunConfig::audit_energy), J.
struct EnergyTotals {
  double energy_start = 0.0;              // kinetic + potential at t = 0
  double energy_end = 0.0;                // ... at the final state
  double work_actuator = 0.0;             // by the actuators
  double work_shove = 0.0;                // by xfrc_applied: the shove, a scenario's disturbances
  double work_passive = 0.0;              // by joint damping (and springs, if any)
  double work_constraint = 0.0;           // by contacts and other constraints
  double work_constraint_positive = 0.0;  // the steps where they added energy
  double unexplained = 0.0;               // (energy_end - energy_start) - all the work
};

struct RunRecord {
  std::string name;  // the scenario's
  std::uint64_t seed = 0;
  std::string rng;  // the generator's name ("mt19937_64", "numpy")
  bool perturb = true;
  std::vector<std::string> disturbed_bodies;  // schedule.forces[i]'s body, by name
  std::vector<Column> columns;
  std::vector<double> final_row;    // the last row, whether kept or streamed
  std::vector<double> final_state;  // the full state at the end (state.hpp's layout)
  Trajectory trajectory;            // empty when the rows went to a RowSink
  std::int64_t rows = 0;            // rows the run recorded, kept or not
  Schedule schedule;                // the drawn inputs, windows as they happened
  std::vector<Warning> warnings;    // MuJoCo's, then simloop's divergence
  double timestep = 0.0;            // the model's timestep during the run
  double sim_time = 0.0;            // mjData::time at the end
  EnergyTotals energy;              // with the energy audit; zeros without
};

// Whether the run had the energy audit (its columns are recorded).
[[nodiscard]] bool audited(const RunRecord& record);

// recorded_bodies(record.columns).
[[nodiscard]] std::map<std::string, std::size_t> recorded_bodies(const RunRecord& record);

}  // namespace simloop
