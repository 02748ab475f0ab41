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

#include "mujoco_compat.hpp"
#include "simloop/run.hpp"

namespace simloop::detail {

class EnergyAudit {
 public:
  explicit EnergyAudit(int nv) : v0_(static_cast<size_t>(nv)), vmid_(v0_.size()), qfrc_(v0_.size()) {}

  // Before mj_step: remember the velocity entering the step.
  void before_step(const mjData* d) noexcept { std::copy(d->qvel, d->qvel + v0_.size(), v0_.begin()); }

  // After mj_step: d->energy holds the energy of the state the step started
  // from (MuJoCo computes it during the step). Returns it; the first call
  // sets the starting energy.
  double observe(const mjData* d) noexcept {
    const double energy = d->energy[0] + d->energy[1];
    if (!started_) {
      totals_.energy_start = energy;
      started_ = true;
    }
    return energy;
  }

  // After mj_step (and observe): adds the work done during the step.
  void add_step_work(const mjModel* m, mjData* d, int box_body) noexcept {
    const int nv = compat::as_int(m->nv);
    const double dt = m->opt.timestep;
    for (int i = 0; i < nv; ++i) vmid_[static_cast<size_t>(i)] = 0.5 * (v0_[static_cast<size_t>(i)] + d->qvel[i]);
    totals_.work_actuator += dt * mju_dot(d->qfrc_actuator, vmid_.data(), nv);
    totals_.work_passive += dt * mju_dot(d->qfrc_passive, vmid_.data(), nv);
    const double constraint = dt * mju_dot(d->qfrc_constraint, vmid_.data(), nv);
    totals_.work_constraint += constraint;
    if (constraint > 0.0) totals_.work_constraint_positive += constraint;
    const double* xfrc = d->xfrc_applied + 6 * box_body;
    if (xfrc[0] != 0.0 || xfrc[1] != 0.0 || xfrc[2] != 0.0 || xfrc[3] != 0.0 || xfrc[4] != 0.0 || xfrc[5] != 0.0) {
      // MuJoCo applies xfrc_applied at the body's centre of mass.
      mju_zero(qfrc_.data(), nv);
      mj_applyFT(m, d, xfrc, xfrc + 3, d->xipos + 3 * box_body, box_body, qfrc_.data());
      totals_.work_shove += dt * mju_dot(qfrc_.data(), vmid_.data(), nv);
    }
  }

  // The audit columns of a row whose state has energy `energy`, with the
  // work done so far.
  void fill_row(double* values, double energy) const noexcept {
    values[ChapterColumns::kEnergy] = energy;
    values[ChapterColumns::kWorkActuator] = totals_.work_actuator;
    values[ChapterColumns::kWorkShove] = totals_.work_shove;
    values[ChapterColumns::kWorkPassive] = totals_.work_passive;
    values[ChapterColumns::kWorkConstraint] = totals_.work_constraint;
    values[ChapterColumns::kWorkConstraintPositive] = totals_.work_constraint_positive;
    values[ChapterColumns::kEnergyUnexplained] = unexplained(energy);
  }

  [[nodiscard]] EnergyTotals totals(double energy_end) const noexcept {
    EnergyTotals t = totals_;
    t.energy_end = energy_end;
    t.unexplained = unexplained(energy_end);
    return t;
  }

 private:
  [[nodiscard]] double unexplained(double energy) const noexcept {
    return (energy - totals_.energy_start) -
           (totals_.work_actuator + totals_.work_shove + totals_.work_passive + totals_.work_constraint);
  }

  std::vector<double> v0_, vmid_, qfrc_;
  EnergyTotals totals_;
  bool started_ = false;
};

}  // namespace simloop::detail
