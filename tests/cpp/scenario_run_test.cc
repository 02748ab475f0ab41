// run_scenario's batches (one scene, one Data per worker, the same bits as
// running each config alone) and a scenario run drawn (every moving body's
// pose beside the trajectory's rows).
#include "simloop/scenario_run.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "run_detail.hpp"
#include "simloop/errors.hpp"
#include "simloop/output.hpp"

namespace {

simloop::Scenario scene_file(const char* name) {
  return simloop::Scenario::from_toml_file(std::string(SIMLOOP_TEST_SCENES) + "/" + name);
}

bool same_bits(const simloop::RunRecord& a, const simloop::RunRecord& b) {
  const simloop::Trajectory& x = a.trajectory;
  const simloop::Trajectory& y = b.trajectory;
  // memcmp, not ==: the final row's input columns hold NaN.
  return x.rows() == y.rows() && x.columns() == y.columns() && a.final_row.size() == b.final_row.size() &&
         std::memcmp(a.final_row.data(), b.final_row.data(), sizeof(double) * a.final_row.size()) == 0 &&
         std::memcmp(x.data(), y.data(),
                     sizeof(double) * static_cast<size_t>(x.rows()) * static_cast<size_t>(x.columns())) == 0;
}

// Seeds and timesteps, as Python's itertools.product(seeds, timesteps).
std::vector<simloop::ScenarioConfig> configs(std::initializer_list<std::uint64_t> seeds,
                                             std::initializer_list<double> timesteps) {
  std::vector<simloop::ScenarioConfig> out;
  for (std::uint64_t seed : seeds) {
    for (double dt : timesteps) {
      simloop::ScenarioConfig c;
      c.seed = seed;
      c.timestep = dt;
      c.perturb = seed != 2;  // one baseline among them: fewer columns
      out.push_back(c);
    }
  }
  return out;
}

void expect_equal_to_sequential(const char* file, const std::vector<simloop::ScenarioConfig>& cs) {
  const simloop::Scenario scenario = scene_file(file);
  const simloop::Model scene = simloop::load_scene(scenario);
  std::vector<simloop::RunRecord> alone;
  for (const auto& c : cs) alone.push_back(simloop::run_scenario(scene, scenario, c));
  for (int threads : {1, 2, 7}) {
    const auto batch = simloop::run_scenario_batch(scene, scenario, cs, threads);
    ASSERT_EQ(batch.size(), cs.size());
    for (size_t i = 0; i < cs.size(); ++i) {
      EXPECT_TRUE(same_bits(batch[i], alone[i])) << file << " run " << i << ", " << threads << " threads";
      EXPECT_EQ(simloop::metrics_json(batch[i]), simloop::metrics_json(alone[i]));
      EXPECT_EQ(simloop::summary_text(batch[i]), simloop::summary_text(alone[i]));
    }
  }
}

TEST(ScenarioColumns, AreTheRunsColumnsAndItsNamesAreChecked) {
  simloop::Scenario scenario = scene_file("pusht.toml");
  const simloop::Model scene = simloop::load_scene(scenario);
  for (bool perturb : {true, false}) {
    simloop::ScenarioConfig config;
    config.steps = 5;
    config.perturb = perturb;
    const simloop::RunRecord run = simloop::run_scenario(scene, scenario, config);
    std::vector<std::string> names;
    for (const simloop::Column& c : run.columns) names.push_back(c.name);
    EXPECT_EQ(simloop::scenario_columns(scene, scenario, config), names) << "perturb " << perturb;
  }
  scenario.record.bodies.push_back("no_such_body");
  EXPECT_THROW((void)simloop::scenario_columns(scene, scenario, {}), simloop::InvalidArgument);
}

TEST(ScenarioBatch, PushTEqualsSequentialRunsWhateverTheThreadCount) {
  expect_equal_to_sequential("pusht.toml", configs({0, 1, 2, 3}, {0.002, 0.004}));
}

TEST(ScenarioBatch, WalkerEqualsSequentialRunsWhateverTheThreadCount) {
  expect_equal_to_sequential("walker.toml", configs({0, 2}, {0.002, 0.005, 0.001}));
}

TEST(ScenarioBatch, RefusesBadConfigsBeforeRunningAny) {
  const simloop::Scenario scenario = scene_file("pusht.toml");
  const simloop::Model scene = simloop::load_scene(scenario);
  auto cs = configs({0, 1}, {0.002, 0.004});
  cs[3].timestep = -1.0;
  try {
    (void)simloop::run_scenario_batch(scene, scenario, cs, 2);
    FAIL() << "accepted";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "run 3: timestep must be a positive, finite number of seconds, got -1.0");
  }
  cs = configs({0, 1}, {0.002});
  cs[1].record_every = 0;
  try {
    (void)simloop::run_scenario_batch(scene, scenario, cs, 2);
    FAIL() << "accepted";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("run 1: record_every must be from 1 to ", 0), 0u) << e.what();
  }
  EXPECT_THROW((void)simloop::run_scenario_batch(scene, scenario, configs({0}, {0.002}), -1), simloop::InvalidArgument);
  EXPECT_TRUE(simloop::run_scenario_batch(scene, scenario, {}, 2).empty());
}

TEST(ScenarioBatch, RefusesKeptRowsThatTogetherWouldNotFit) {
  // Each run alone fits the budget; the batch of them does not.
  const simloop::Scenario scenario = scene_file("pusht.toml");
  const simloop::Model scene = simloop::load_scene(scenario);
  const std::uint64_t budget = simloop::trajectory_memory_budget();
  simloop::ScenarioConfig c;
  const auto one = simloop::run_scenario(scene, scenario, [] {
    simloop::ScenarioConfig s;
    s.steps = 1;
    return s;
  }());
  const auto width = static_cast<std::uint64_t>(one.columns.size());
  c.steps = static_cast<std::int64_t>(budget / (width * sizeof(double)) / 2 + 1);  // a little over half
  std::vector<simloop::ScenarioConfig> cs(3, c);
  try {
    (void)simloop::run_scenario_batch(scene, scenario, cs, 2);
    FAIL() << "accepted";
  } catch (const simloop::InvalidArgument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("(run 0, the largest of 3 runs) and the others would keep"), std::string::npos) << message;
    EXPECT_NE(message.find("raise record_every"), std::string::npos) << message;
  }
}

TEST(ScenarioBatch, AFailedThreadStartLeavesFewerWorkersAndTheSameResults) {
  const simloop::Scenario scenario = scene_file("pusht.toml");
  const simloop::Model scene = simloop::load_scene(scenario);
  const auto cs = configs({0, 1, 3}, {0.002});
  const auto full = simloop::run_scenario_batch(scene, scenario, cs, 3);
  simloop::detail::limit_thread_starts_for_testing(1);
  const auto fewer = simloop::run_scenario_batch(scene, scenario, cs, 3);
  simloop::detail::limit_thread_starts_for_testing(-1);
  for (size_t i = 0; i < cs.size(); ++i) EXPECT_TRUE(same_bits(full[i], fewer[i])) << "run " << i;
}

TEST(ScenarioBatch, AStopEndsTheBatchAndProgressCountsEveryRun) {
  const simloop::Scenario scenario = scene_file("pusht.toml");
  const simloop::Model scene = simloop::load_scene(scenario);
  const auto cs = configs({0, 1, 3}, {0.002});
  simloop::RunControl watched;
  (void)simloop::run_scenario_batch(scene, scenario, cs, 2, &watched);
  EXPECT_EQ(watched.steps_total(), 3 * 1000);
  EXPECT_EQ(watched.steps_done(), 3 * 1000);
  simloop::RunControl stopped;
  stopped.request_stop();
  EXPECT_THROW((void)simloop::run_scenario_batch(scene, scenario, cs, 2, &stopped), simloop::Interrupted);
}

// A policy that fails in one run of a batch: the others stop at their next
// chunk instead of running to their end (Ctrl-C raised inside a Python
// policy is such a failure), and the failure is what the batch throws.
TEST(ScenarioBatch, AFailingRunStopsTheOthersAtTheirNextChunk) {
  const simloop::Scenario scenario = scene_file("pusht.toml");
  const simloop::Model scene = simloop::load_scene(scenario);
  std::vector<simloop::ScenarioConfig> cs(2);
  for (auto& c : cs) c.steps = 50'000'000;  // minutes each, if not stopped
  // One policy per run: run 1's fails at step 2000.
  class Counting final : public simloop::Policy {
   public:
    explicit Counting(bool fail) : Policy(1), fail_(fail) {}
    void decide(std::int64_t step, const double*, int, std::vector<double>& ctrl) override {
      if (fail_ && step == 2000) throw std::runtime_error("the policy failed (test)");
      std::fill(ctrl.begin(), ctrl.end(), 0.5);
    }

   private:
    bool fail_;
  } runs_on(false), fails(true);
  const std::vector<simloop::RunInputs> inputs = {simloop::RunInputs::deciding(runs_on),
                                                  simloop::RunInputs::deciding(fails)};
  simloop::RunControl control;
  const auto started = std::chrono::steady_clock::now();
  try {
    (void)simloop::run_scenario_batch(scene, scenario, cs, 2, &control, inputs, false);
    FAIL() << "the batch did not fail";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "the policy failed (test)");
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  EXPECT_LT(seconds, 5.0) << "the other run went on after the failure";
  EXPECT_FALSE(control.stop_requested()) << "a failure is not the owner's stop";
  EXPECT_FALSE(control.batch_abandoned()) << "cleared for the control's next batch";
}

// Collects what a sink is given.
class Collect final : public simloop::RowSink {
 public:
  void describe(const std::vector<simloop::Column>& columns) override { names = columns; }
  void start(int columns, std::int64_t rows) override {
    width = columns;
    expected_rows = rows;
  }
  void write(const double* rows, std::int64_t count) override {
    values.insert(values.end(), rows, rows + count * width);
  }
  std::vector<simloop::Column> names;
  int width = 0;
  std::int64_t expected_rows = 0;
  std::vector<double> values;
};

TEST(ScenarioDrawn, TheTrajectoryIsUnchangedAndEveryMovingBodyHasItsPoseAndEveryRowItsQpos) {
  const simloop::Scenario scenario = scene_file("walker.toml");
  const simloop::Model scene = simloop::load_scene(scenario);
  const std::vector<std::string> moving = simloop::moving_bodies(scene);
  // The torso (free) and the legs (hinges), which the scenario does not record.
  EXPECT_GE(moving.size(), 5u);
  EXPECT_NE(std::find(moving.begin(), moving.end(), "torso"), moving.end());
  simloop::ScenarioConfig config;
  config.record_every = 7;
  const simloop::RunRecord kept = simloop::run_scenario(scene, scenario, config);
  Collect rows, drawing;
  const simloop::RunRecord drawn = simloop::run_scenario_drawn(scene, scenario, config, rows, drawing);
  ASSERT_EQ(rows.width, kept.trajectory.columns());
  ASSERT_EQ(rows.values.size(), static_cast<size_t>(kept.trajectory.rows() * kept.trajectory.columns()));
  EXPECT_EQ(std::memcmp(rows.values.data(), kept.trajectory.data(), rows.values.size() * sizeof(double)), 0);
  ASSERT_EQ(drawn.columns.size(), kept.columns.size());
  for (size_t c = 0; c < kept.columns.size(); ++c) EXPECT_EQ(drawn.columns[c].name, kept.columns[c].name);
  EXPECT_EQ(std::memcmp(drawn.final_row.data(), kept.final_row.data(), kept.final_row.size() * sizeof(double)), 0);
  EXPECT_EQ(simloop::metrics_json(drawn), simloop::metrics_json(kept));
  // The drawing: the same values, then x y z qw qx qy qz per moving body,
  // then qpos (every joint's position, in order).
  const int width = kept.trajectory.columns();
  const int nq = scene.get()->nq;
  ASSERT_EQ(drawing.width, width + 7 * static_cast<int>(moving.size()) + nq);
  ASSERT_EQ(drawing.names.size(), static_cast<size_t>(drawing.width));
  EXPECT_EQ(drawing.names[static_cast<size_t>(width)].name, moving[0] + "_x");
  const std::size_t torso = simloop::recorded_bodies(kept).at("torso");
  const std::size_t torso_pose =
      static_cast<size_t>(width) +
      7 * static_cast<size_t>(std::find(moving.begin(), moving.end(), "torso") - moving.begin());
  const mjModel* m = scene.get();
  for (std::int64_t r = 0; r < kept.trajectory.rows(); ++r) {
    const double* row = drawing.values.data() + r * drawing.width;
    EXPECT_EQ(std::memcmp(row, kept.trajectory.row(r), static_cast<size_t>(width) * sizeof(double)), 0);
    EXPECT_EQ(std::memcmp(row + torso_pose, kept.trajectory.row(r) + torso, 7 * sizeof(double)), 0);
    for (size_t b = 0; b < moving.size(); ++b) {  // unit quaternions, finite positions
      const double* q = row + width + 7 * b + 3;
      EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0, 1e-9);
    }
  }
  const double* first = drawing.values.data();
  const double* last = drawing.values.data() + (kept.trajectory.rows() - 1) * drawing.width;
  const int qpos = width + 7 * static_cast<int>(moving.size());
  EXPECT_EQ(drawing.names[static_cast<size_t>(qpos)].name, simloop::joint_position_columns(scene.get(), 0)[0]);
  for (int i = 0; i < nq; ++i) {
    EXPECT_EQ(first[qpos + i], scene.get()->qpos0[i]) << i;                         // the start...
    EXPECT_EQ(last[qpos + i], drawn.final_state[1 + static_cast<size_t>(i)]) << i;  // ...and the end (after time)
  }
  // A leg moves relative to the torso over the run (its hinge turns).
  const int leg = mj_name2id(m, mjOBJ_BODY, moving.back().c_str());
  ASSERT_GE(leg, 0);
  EXPECT_NE(m->body_jntnum[leg], 0);
}

}  // namespace
