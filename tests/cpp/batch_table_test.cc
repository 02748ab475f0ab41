// A batch's table (batch_table.hpp): each run reduced to its row as it ends
// gives the table of the kept records, bit for bit, whatever the thread count.
#include "simloop/batch_table.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "simloop/errors.hpp"

namespace {

simloop::Scenario pusht() {
  return simloop::Scenario::from_toml_file(std::string(SIMLOOP_TEST_SCENES) + "/pusht.toml");
}

// Four seeds at two timesteps; seed 2 a baseline (no disturbance: a row of fewer columns).
std::vector<simloop::ScenarioConfig> configs() {
  std::vector<simloop::ScenarioConfig> out;
  for (std::uint64_t seed : {0, 1, 2, 3}) {
    for (double dt : {0.002, 0.004}) {
      simloop::ScenarioConfig c;
      c.seed = seed;
      c.timestep = dt;
      c.steps = 300;
      c.perturb = seed != 2;
      out.push_back(c);
    }
  }
  return out;
}

std::vector<std::string> names(const std::vector<simloop::TableColumn>& layout) {
  std::vector<std::string> out;
  for (const simloop::TableColumn& c : layout) out.push_back(c.name);
  return out;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

TEST(BatchTable, ReducedRunByRunIsTheTableOfTheKeptRecords) {
  const simloop::Scenario scenario = pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  const std::vector<simloop::ScenarioConfig> cs = configs();
  const std::vector<simloop::RunRecord> kept = simloop::run_scenario_batch(scene, scenario, cs, 1);
  std::vector<const simloop::RunRecord*> records;
  for (const simloop::RunRecord& r : kept) records.push_back(&r);
  const simloop::ScenarioTable expected = simloop::scenario_table(records);
  // Two layouts, in the order runs first had them: the perturbed runs' and the baseline's.
  ASSERT_EQ(expected.layouts.size(), 2u);
  const std::vector<std::string> first = names(expected.layouts[0]), second = names(expected.layouts[1]);
  EXPECT_EQ(first.front(), "pusher_final_pos_x");  // the bodies by name, then the disturbances
  const auto column = [&](const char* name) {
    return static_cast<std::size_t>(std::find(first.begin(), first.end(), name) - first.begin());
  };
  const std::size_t pos_y = column("tblock_final_pos_y"), speed = column("tblock_final_speed");
  ASSERT_LT(speed, first.size());
  EXPECT_NE(std::find(first.begin(), first.end(), "disturbance0_start_step"), first.end());
  EXPECT_EQ(std::find(second.begin(), second.end(), "disturbance0_fy"), second.end());
  for (std::size_t i = 0; i < cs.size(); ++i) {
    const simloop::TableRow& row = expected.rows[i];
    EXPECT_EQ(row.layout, cs[i].perturb ? 0u : 1u) << i;
    EXPECT_EQ(row.seed, cs[i].seed);
    EXPECT_EQ(row.steps, kept[i].schedule.steps);
    const std::size_t body = simloop::recorded_bodies(kept[i]).at("tblock");
    EXPECT_EQ(row.values[pos_y], kept[i].final_row[body + 1]) << i;
    const double* v = kept[i].final_row.data() + body + 7;
    EXPECT_EQ(row.values[speed], simloop::final_speed(v[0], v[1], v[2]));
  }
  for (int threads : {1, 2, 7}) {
    const simloop::ScenarioTable lean = simloop::run_scenario_table(scene, scenario, cs, threads);
    ASSERT_EQ(lean.layouts.size(), expected.layouts.size()) << threads;
    for (std::size_t k = 0; k < lean.layouts.size(); ++k) {
      EXPECT_EQ(names(lean.layouts[k]), names(expected.layouts[k])) << threads;
    }
    ASSERT_EQ(lean.rows.size(), cs.size());
    for (std::size_t i = 0; i < cs.size(); ++i) {
      const simloop::TableRow &a = lean.rows[i], &b = expected.rows[i];
      EXPECT_TRUE(same_bits(a.values, b.values)) << "run " << i << ", " << threads << " threads";
      EXPECT_EQ(a.layout, b.layout);
      EXPECT_EQ(a.warnings, b.warnings);
      EXPECT_EQ(a.sim_time, b.sim_time);
      EXPECT_EQ(a.scenario, "pusht");
    }
  }
}

TEST(BatchTable, RefusesABadRunBeforeRunningAny) {
  const simloop::Scenario scenario = pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  std::vector<simloop::ScenarioConfig> cs = configs();
  cs[5].timestep = -1.0;
  try {
    (void)simloop::run_scenario_table(scene, scenario, cs, 2);
    FAIL() << "accepted";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "run 5: timestep must be a positive, finite number of seconds, got -1.0");
  }
}

TEST(BatchTable, AFinalSpeedIsFiniteWheneverTheVelocityIs) {
  EXPECT_EQ(simloop::final_speed(3.0, 4.0, 12.0), 13.0);
  const double big = 1e200;  // its square is past double's range
  const double speed = simloop::final_speed(big, big, 0.0);
  EXPECT_TRUE(std::isfinite(speed));
  EXPECT_NEAR(speed / big, std::sqrt(2.0), 1e-15);
  EXPECT_TRUE(std::isinf(simloop::final_speed(std::numeric_limits<double>::infinity(), 0.0, 0.0)));
}

}  // namespace

TEST(BatchTable, AGoalsDrawnPositionIsThreeColumnsAndOnlyWhereAScenarioHasGoals) {
  const simloop::Model scene = simloop::Model::from_xml_string(
      "<mujoco><worldbody><body name=\"target\" mocap=\"true\"><geom size=\"0.1\" contype=\"0\" "
      "conaffinity=\"0\"/></body><body name=\"ball\" pos=\"0 0 1\"><freejoint/><geom size=\"0.1\"/></body>"
      "</worldbody></mujoco>");
  const std::string base = "steps = 5\n[record]\nbodies = [\"target\"]\n";
  const simloop::Scenario goal = simloop::Scenario::from_toml_string(
      base + "[[reset.goal]]\nbody = \"target\"\nuniform = [[0, 0, 0.5], [1, 2, 0.5]]\n", "goal.toml");
  std::vector<simloop::ScenarioConfig> runs(2);
  runs[1].seed = 1;
  const simloop::ScenarioTable t = simloop::run_scenario_table(scene, goal, runs, 1);
  ASSERT_EQ(t.layouts.size(), 1u);
  const std::vector<std::string> columns = names(t.layouts[0]);
  ASSERT_GE(columns.size(), 3u);
  EXPECT_EQ(std::vector<std::string>(columns.end() - 3, columns.end()),
            (std::vector<std::string>{"goal_target_x", "goal_target_y", "goal_target_z"}));
  for (const simloop::TableRow& row : t.rows) {
    const double* xyz = row.values.data() + row.values.size() - 3;
    EXPECT_TRUE(xyz[0] >= 0 && xyz[0] < 1 && xyz[1] >= 0 && xyz[1] < 2 && xyz[2] == 0.5);
    // The drawn position is where the run put the body (its recorded final position: a mocap body stays).
    EXPECT_EQ(row.values[0], xyz[0]);
    EXPECT_EQ(row.values[1], xyz[1]);
  }
  EXPECT_NE(t.rows[0].values[0], t.rows[1].values[0]);  // each seed its own draw
  const simloop::ScenarioTable plain =
      simloop::run_scenario_table(scene, simloop::Scenario::from_toml_string(base, "plain.toml"), runs, 1);
  for (const std::string& name : names(plain.layouts.at(0))) EXPECT_EQ(name.rfind("goal_", 0), std::string::npos);
}
