// The energy audit (internal): where every joule of a run came from.
//
// Per step, with v0 the velocity entering the step and v1 the one leaving it,
// a force f does work dt * f . (v0 + v1) / 2: for MuJoCo's semi-implicit Euler
// with a constant mass matrix that is exactly its share of the kinetic-energy
// change. The forces are the ones the step itself computed (qfrc_actuator,
// qfrc_passive, qfrc_constraint, and the shove mapped through mj_applyFT);
// gravity is in the potential energy. What these do not account for, the
// change in kinetic + potential energy minus all the work, is energy the
// integrator made or destroyed: the chapter's "energy from nowhere" when it
// is positive, and the integrator's own damping when it is negative.
#pragma once

#include <mujoco/mujoco.h>

#include <algorithm>
#include <vector>

#include "loop.hpp"
#include "mujoco_compat.hpp"
#include "simloop/run_record.hpp"

namespace simloop::detail {

// The audit as the loop sees it: it watches every step and, when the run
// records the audit's columns (from `first_column` on, Recorder's order),
// fills them in each row. `pushed`: the bodies the schedule's forces act on.
class EnergyAudit final : public StepObserver {
 public:
  EnergyAudit(int nv, std::vector<int> pushed, int first_column)
      : v0_(static_cast<size_t>(nv)),
        vmid_(v0_.size()),
        qfrc_(v0_.size()),
        pushed_(std::move(pushed)),
        first_column_(first_column) {}

  // Before mj_step: remember the velocity entering the step.
  void before_step(std::int64_t /*step*/, const mjModel* /*m*/, const mjData* d) noexcept override {
    std::copy(d->qvel, d->qvel + v0_.size(), v0_.begin());
  }

  // After mj_step: d->energy holds the energy of the state the step started
  // from (MuJoCo computes it during the step), which is the row's; the work
  // done before this step is what the row holds. Then this step's work.
  void after_step(std::int64_t /*step*/, const mjModel* m, mjData* d, double* row) noexcept override {
    const double energy = d->energy[0] + d->energy[1];
    if (!started_) {
      totals_.energy_start = energy;
      started_ = true;
    }
    if (row) fill_row(row, energy);
    add_step_work(m, d);
  }

  // After the final mj_forward, which computed the final state's energy.
  void at_end(const mjModel* /*m*/, const mjData* d, double* row) noexcept override {
    final_energy_ = d->energy[0] + d->energy[1];
    fill_row(row, final_energy_);
  }

  [[nodiscard]] EnergyTotals totals() const noexcept {
    EnergyTotals t = totals_;
    t.energy_end = final_energy_;
    t.unexplained = unexplained(final_energy_);
    return t;
  }

 private:
  void add_step_work(const mjModel* m, mjData* d) noexcept {
    const int nv = compat::as_int(m->nv);
    const double dt = m->opt.timestep;
    for (int i = 0; i < nv; ++i) vmid_[static_cast<size_t>(i)] = 0.5 * (v0_[static_cast<size_t>(i)] + d->qvel[i]);
    totals_.work_actuator += dt * mju_dot(d->qfrc_actuator, vmid_.data(), nv);
    totals_.work_passive += dt * mju_dot(d->qfrc_passive, vmid_.data(), nv);
    const double constraint = dt * mju_dot(d->qfrc_constraint, vmid_.data(), nv);
    totals_.work_constraint += constraint;
    if (constraint > 0.0) totals_.work_constraint_positive += constraint;
    for (const int body : pushed_) {
      const double* xfrc = d->xfrc_applied + 6 * body;
      if (xfrc[0] != 0.0 || xfrc[1] != 0.0 || xfrc[2] != 0.0 || xfrc[3] != 0.0 || xfrc[4] != 0.0 || xfrc[5] != 0.0) {
        // MuJoCo applies xfrc_applied at the body's centre of mass.
        mju_zero(qfrc_.data(), nv);
        mj_applyFT(m, d, xfrc, xfrc + 3, d->xipos + 3 * body, body, qfrc_.data());
        totals_.work_shove += dt * mju_dot(qfrc_.data(), vmid_.data(), nv);
      }
    }
  }

  // The audit's columns of a row whose state has energy `energy`, with the
  // work done so far.
  void fill_row(double* row, double energy) const noexcept {
    if (first_column_ < 0) return;
    double* values = row + first_column_;
    values[0] = energy;
    values[1] = totals_.work_actuator;
    values[2] = totals_.work_shove;
    values[3] = totals_.work_passive;
    values[4] = totals_.work_constraint;
    values[5] = totals_.work_constraint_positive;
    values[6] = unexplained(energy);
  }

  [[nodiscard]] double unexplained(double energy) const noexcept {
    return (energy - totals_.energy_start) -
           (totals_.work_actuator + totals_.work_shove + totals_.work_passive + totals_.work_constraint);
  }

  std::vector<double> v0_, vmid_, qfrc_;
  std::vector<int> pushed_;
  int first_column_;
  EnergyTotals totals_;
  bool started_ = false;
  double final_energy_ = 0.0;
};

}  // namespace simloop::detail
