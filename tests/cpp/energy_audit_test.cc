// The energy audit (cpp/energy_audit.hpp, RunConfig::audit_energy): it
// changes no physics, its columns add up row by row, and it tells the stable
// run from the unstable one.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "expected.hpp"
#include "simloop/output.hpp"
#include "simloop/run.hpp"
#include "simloop/scenario_run.hpp"

namespace {

using simloop::ChapterColumns;
using simloop::Trajectory;

const simloop::Model& scene() {
  static const simloop::Model model = simloop::pusher_scene();
  return model;
}

simloop::RunResult audited(double timestep, std::int64_t steps, bool perturb) {
  simloop::RunConfig c;
  c.timestep = timestep;
  c.steps = steps;
  c.perturb = perturb;
  c.audit_energy = true;
  return simloop::run(scene(), c);
}

TEST(EnergyAudit, ChangesNoPhysics) {
  simloop::RunConfig plain;
  plain.steps = 1200;
  simloop::RunConfig audit = plain;
  audit.audit_energy = true;
  const auto a = simloop::run(scene(), plain);
  const auto b = simloop::run(scene(), audit);
  ASSERT_EQ(a.trajectory.columns(), ChapterColumns::kNumBaseColumns);
  ASSERT_EQ(b.trajectory.columns(), ChapterColumns::kNumColumns);
  for (std::int64_t r = 0; r < a.trajectory.rows(); ++r) {
    ASSERT_EQ(std::memcmp(a.trajectory.row(r), b.trajectory.row(r), sizeof(double) * ChapterColumns::kNumBaseColumns),
              0)
        << "row " << r;
  }
  EXPECT_EQ(simloop::metrics_json(a.metrics), simloop::metrics_json(b.metrics));
}

TEST(EnergyAudit, ColumnsAddUpRowByRow) {
  const auto r = audited(0.002, 2000, true);
  const Trajectory& t = r.trajectory;
  const double e0 = t.at(0, ChapterColumns::kEnergy);
  // At rest: potential m g z of the box (0.5 kg at 0.05 m) and pusher (1 kg at 0.05 m).
  EXPECT_NEAR(e0, 1.5 * 9.81 * 0.05, 1e-9);
  for (std::int64_t row = 0; row < t.rows(); ++row) {
    const double work = t.at(row, ChapterColumns::kWorkActuator) + t.at(row, ChapterColumns::kWorkShove) +
                        t.at(row, ChapterColumns::kWorkPassive) + t.at(row, ChapterColumns::kWorkConstraint);
    ASSERT_NEAR(t.at(row, ChapterColumns::kEnergyUnexplained), t.at(row, ChapterColumns::kEnergy) - e0 - work, 1e-9);
  }
  const simloop::EnergyTotals& e = r.energy;
  EXPECT_EQ(e.energy_end, t.at(t.rows() - 1, ChapterColumns::kEnergy));
  EXPECT_GT(e.work_actuator, 10.0);   // the motor drives everything
  EXPECT_LT(e.work_passive, -5.0);    // damping takes energy out
  EXPECT_LT(e.work_constraint, 0.0);  // friction takes energy out
  EXPECT_GT(e.work_shove, 0.0);       // the shove put some in
  // At a sound timestep the known forces explain nearly everything: measured
  // -0.0076 J unexplained out of +47.6 J of motor work.
  EXPECT_LT(std::fabs(e.unexplained), 0.02);
  EXPECT_EQ(audited(0.002, 300, false).energy.work_shove, 0.0);
}

// Measured over 4 s without the shove: contacts' positive work 0.0354 J at
// 0.002 s and 0.2991 J at 0.05 s; unexplained -0.0051 J and -0.1015 J.
TEST(EnergyAudit, SeparatesTheStableRunFromTheUnstableOne) {
  const auto fine = audited(0.002, 2000, false);
  const auto coarse = audited(0.05, 80, false);
  SIMLOOP_EXPECTED(double, fine_positive_max, "energy_audit.fine_positive_contact_work_max");
  EXPECT_LT(fine.energy.work_constraint_positive, fine_positive_max);
  EXPECT_GT(coarse.energy.work_constraint_positive, 0.2);
  EXPECT_GT(coarse.energy.work_constraint_positive, 5 * fine.energy.work_constraint_positive);
  EXPECT_LT(std::fabs(fine.energy.unexplained), 0.01);
  EXPECT_GT(std::fabs(coarse.energy.unexplained), 5 * std::fabs(fine.energy.unexplained));
  EXPECT_NE(simloop::summary_text(coarse).find("energy audit: change "), std::string::npos);
}

// The audit is the scenario's: a scenario run with it has the same columns,
// bit for bit, as the chapter's, and the same totals, and a scenario with
// two pushed bodies counts the work of both.
TEST(EnergyAudit, AScenarioRunAuditsAsTheChapterDoes) {
  simloop::RunConfig chapter;
  chapter.seed = 3;
  chapter.audit_energy = true;
  const auto expected = simloop::run(scene(), chapter);
  const simloop::RunRecord got =
      simloop::run_scenario(scene(), simloop::Scenario::chapter(), simloop::scenario_config(chapter));
  const auto column = [&](const simloop::RunRecord& r, const std::string& name) {
    for (std::size_t c = 0; c < r.columns.size(); ++c) {
      if (r.columns[c].name == name) return static_cast<int>(c);
    }
    return -1;
  };
  for (int c = ChapterColumns::kEnergy; c < ChapterColumns::kNumColumns; ++c) {
    const int at = column(got, std::string(ChapterColumns::kNames[c]));
    ASSERT_GE(at, 0) << ChapterColumns::kNames[c];
    for (std::int64_t row = 0; row < got.trajectory.rows(); ++row) {
      const double a = got.trajectory.at(row, at), b = expected.trajectory.at(row, c);
      ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0) << ChapterColumns::kNames[c] << " row " << row;
    }
  }
  EXPECT_EQ(std::memcmp(&got.energy, &expected.energy, sizeof got.energy), 0);
  EXPECT_GT(got.energy.work_shove, 0.0);

  simloop::Scenario both = simloop::Scenario::chapter();
  both.disturbances.push_back(both.disturbances.front());
  both.disturbances.back().body = "pusher";
  both.disturbances.back().force = {1.0, 0.0, 0.0};  // along its slide: y would do no work
  const simloop::RunRecord two = simloop::run_scenario(scene(), both, simloop::scenario_config(chapter));
  EXPECT_NE(two.energy.work_shove, got.energy.work_shove);
  EXPECT_LT(std::fabs(two.energy.unexplained), 0.05);  // the pusher's push is accounted for too
  simloop::ScenarioConfig plain = simloop::scenario_config(chapter);
  plain.audit_energy = false;
  const simloop::RunRecord unaudited = simloop::run_scenario(scene(), simloop::Scenario::chapter(), plain);
  EXPECT_EQ(column(unaudited, "energy"), -1);
  EXPECT_EQ(unaudited.energy.energy_start, 0.0);
}

}  // namespace
