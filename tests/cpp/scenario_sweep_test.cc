// sweep_scenario: a scenario swept over timesteps, each point bitwise the run
// alone, blowing up on warnings or on distance.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/sweep.hpp"

namespace {

simloop::Scenario scene_file(const char* name) {
  return simloop::Scenario::from_toml_file(std::string(SIMLOOP_TEST_SCENES) + "/" + name);
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The run a sweep point stands for, kept in memory.
simloop::RunRecord alone(const simloop::Model& scene, const simloop::Scenario& scenario, double dt, double duration) {
  simloop::ScenarioConfig c;
  c.timestep = dt;
  c.steps = simloop::sweep_steps(duration, dt);
  return simloop::run_scenario(scene, scenario, c);
}

TEST(ScenarioSweep, EachPointIsBitwiseTheRunAloneAndTheFinestIsTheReference) {
  const simloop::Scenario scenario = scene_file("pusht.toml");
  const simloop::Model scene = simloop::load_scene(scenario);
  const double duration = 0.6;
  // Unsorted, with a duplicate: sorted and deduplicated.
  const simloop::ScenarioSweepResult swept =
      simloop::sweep_scenario(scene, scenario, {0.004, 0.001, 0.03, 0.002, 0.001}, duration, {}, 2);
  ASSERT_EQ(swept.points.size(), 4u);
  EXPECT_EQ(swept.bodies, (std::vector<std::string>{"tblock", "pusher"}));  // the columns' order
  EXPECT_EQ(swept.duration, duration);
  EXPECT_EQ(swept.scene_size, scene.get()->stat.extent);
  EXPECT_EQ(swept.tolerance, simloop::kScenarioSweepTolerance * scene.get()->stat.extent);
  const std::map<std::string, std::size_t> columns = simloop::recorded_bodies(alone(scene, scenario, 0.001, 0.01));
  std::vector<std::array<double, 3>> reference;
  for (std::size_t i = 0; i < swept.points.size(); ++i) {
    const simloop::ScenarioSweepPoint& p = swept.points[i];
    const simloop::RunRecord run = alone(scene, scenario, p.timestep, duration);
    EXPECT_EQ(p.steps, run.schedule.steps);
    // The largest speed over every row, and the final positions: the same bits.
    double peak = 0.0;
    for (std::int64_t r = 0; r < run.trajectory.rows(); ++r) {
      for (const auto& [name, c] : columns) {
        const double* v = run.trajectory.row(r) + c + 7;
        peak = std::max(peak, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
      }
    }
    EXPECT_TRUE(same_bits(p.peak_speed, peak)) << p.timestep;
    for (std::size_t b = 0; b < swept.bodies.size(); ++b) {
      const double* final = run.final_row.data() + columns.at(swept.bodies[b]);
      EXPECT_EQ(std::memcmp(p.final_positions[b].data(), final, 3 * sizeof(double)), 0) << p.timestep;
    }
    if (i == 0) reference = p.final_positions;
    for (std::size_t b = 0; b < swept.bodies.size(); ++b) {
      const auto& a = p.final_positions[b];
      const auto& ref = reference[b];
      EXPECT_DOUBLE_EQ(p.offsets[b], std::hypot(a[0] - ref[0], a[1] - ref[1], a[2] - ref[2]));
    }
    EXPECT_EQ(p.mujoco_warnings + p.diverged, 0);
  }
  EXPECT_EQ(swept.points[0].max_offset, 0.0);
  EXPECT_FALSE(swept.points[0].blew_up);
  // The same sweep on one thread: the same bits.
  const simloop::ScenarioSweepResult serial =
      simloop::sweep_scenario(scene, scenario, {0.001, 0.002, 0.004, 0.03}, duration, {}, 1);
  EXPECT_EQ(simloop::sweep_csv(serial), simloop::sweep_csv(swept));
}

TEST(ScenarioSweep, BlowsUpOnWarningsOrOnDistanceAndNamesTheEdge) {
  const simloop::Scenario scenario = scene_file("walker.toml");
  const simloop::Model scene = simloop::load_scene(scenario);
  const double duration = simloop::scenario_duration(scene, scenario);
  EXPECT_DOUBLE_EQ(duration, 750 * 0.004);  // steps = 750 at the scene's 0.004 s
  const simloop::ScenarioSweepResult swept =
      simloop::sweep_scenario(scene, scenario, {0.001, 0.002, 0.2, 0.3}, duration);
  const simloop::ScenarioSweepPoint& coarse = swept.points[2];
  ASSERT_EQ(coarse.timestep, 0.2);
  // At 0.2 s the walker's state goes bad: MuJoCo warns, and that alone blows it up.
  EXPECT_GT(coarse.mujoco_warnings + coarse.diverged, 0);
  EXPECT_TRUE(coarse.blew_up);
  EXPECT_GT(coarse.peak_speed, 100.0);
  EXPECT_FALSE(swept.points[0].blew_up);
  EXPECT_LT(swept.edge_index, 2);
  for (const simloop::ScenarioSweepPoint& p : swept.points) {
    EXPECT_EQ(p.blew_up, p.mujoco_warnings > 0 || p.diverged > 0 || !(p.max_offset <= swept.tolerance));
  }
  // PushT at 0.03 s raises no warning but ends its block far from the
  // reference: it blew up by distance alone.
  const simloop::Scenario pusht = scene_file("pusht.toml");
  const simloop::Model pusht_scene = simloop::load_scene(pusht);
  const simloop::ScenarioSweepResult far = simloop::sweep_scenario(pusht_scene, pusht, {0.0005, 0.03}, 2.0);
  EXPECT_EQ(far.points[1].mujoco_warnings + far.points[1].diverged, 0);
  EXPECT_GT(far.points[1].max_offset, far.tolerance);
  EXPECT_TRUE(far.points[1].blew_up);
  EXPECT_EQ(far.edge_index, 0);
  const std::string summary = simloop::sweep_summary(far);
  EXPECT_NE(summary.find("largest timestep before any blew up: 0.0005 s"), std::string::npos) << summary;
  const std::string csv = simloop::sweep_csv(far);
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "timestep,steps,mujoco_warnings,diverged,peak_speed,tblock_final_x,tblock_final_y,tblock_final_z,"
            "tblock_offset,pusher_final_x,pusher_final_y,pusher_final_z,pusher_offset,max_offset,tolerance,blew_up");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3);
}

TEST(ScenarioSweep, RefusesBadInputBeforeAnyRun) {
  const simloop::Scenario scenario = scene_file("pusht.toml");
  const simloop::Model scene = simloop::load_scene(scenario);
  EXPECT_THROW((void)simloop::sweep_scenario(scene, scenario, {}, 1.0), simloop::InvalidArgument);
  EXPECT_THROW((void)simloop::sweep_scenario(scene, scenario, {0.001}, -1.0), simloop::InvalidArgument);
  EXPECT_THROW((void)simloop::sweep_scenario(scene, scenario, {0.5}, 1.0), simloop::InvalidArgument);  // 2 steps
  EXPECT_THROW((void)simloop::sweep_scenario(scene, scenario, {0.001}, 1.0, {}, -1), simloop::InvalidArgument);
  // The default grid keeps only timesteps that give 4 steps or more.
  const std::vector<double> grid = simloop::default_scenario_sweep_timesteps(2.0);
  EXPECT_EQ(grid.front(), 0.0005);
  EXPECT_EQ(grid.back(), 0.5);
  EXPECT_TRUE(simloop::default_scenario_sweep_timesteps(0.001).empty());
}

}  // namespace
