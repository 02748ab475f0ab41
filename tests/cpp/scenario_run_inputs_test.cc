// The caller's own controls and initial states (RunInputs), and batches that
// keep no rows: the same bits as a hand-written mj_step loop, as running each
// run alone, and as one long run cut in two.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/output.hpp"
#include "simloop/recorder.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/state.hpp"

namespace {

simloop::Scenario pusht() {
  return simloop::Scenario::from_toml_file(std::string(SIMLOOP_TEST_SCENES) + "/pusht.toml");
}

// steps x nu controls drawn from `seed`, some outside ctrlrange (MuJoCo clamps).
std::vector<double> random_controls(std::uint64_t seed, std::int64_t steps, int nu) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::vector<double> out(static_cast<size_t>(steps) * static_cast<size_t>(nu));
  for (double& v : out) v = u(gen);
  return out;
}

simloop::RunInputs controls_input(const std::vector<double>& u, std::int64_t steps, int nu) {
  simloop::RunInputs in;
  in.controls = u.data();
  in.control_steps = steps;
  in.control_width = nu;
  return in;
}

bool same(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

simloop::ScenarioConfig config(std::uint64_t seed, std::int64_t steps, bool perturb) {
  simloop::ScenarioConfig c;
  c.seed = seed;
  c.steps = steps;
  c.perturb = perturb;
  return c;
}

TEST(BatchControls, OwnControlsGiveTheBitsOfAHandWrittenLoop) {
  const simloop::Scenario scenario = pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  const int nu = scene.get()->nu;
  const std::int64_t steps = 300;
  const std::vector<double> u = random_controls(7, steps, nu);
  const simloop::RunRecord r = simloop::run_scenario(scene, scenario, config(0, steps, false), nullptr, nullptr,
                                                     nullptr, controls_input(u, steps, nu));

  // The loop as a user writes it with MuJoCo alone.
  simloop::Data data(scene);
  const mjModel* m = scene.get();
  mjData* d = data.get();
  mj_resetData(m, d);
  mj_forward(m, d);
  for (std::int64_t t = 0; t < steps; ++t) {
    for (int a = 0; a < nu; ++a) d->ctrl[a] = u[static_cast<size_t>(t * nu + a)];
    mj_step(m, d);
  }
  EXPECT_TRUE(same(r.final_state, simloop::get_state(m, d)));
  // The recorded ctrl is what MuJoCo applied: the caller's, clamped.
  const auto& cols = r.columns;
  for (size_t c = 0; c < cols.size(); ++c) {
    if (cols[c].name == "push_x_ctrl")
      EXPECT_EQ(r.trajectory.at(5, static_cast<int>(c)), std::clamp(u[5 * nu], -1.0, 1.0));
  }
}

TEST(BatchControls, ABatchOfOwnControlsEqualsRunningEachAloneAtOneAndTwoThreads) {
  const simloop::Scenario scenario = pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  const int nu = scene.get()->nu;
  const std::int64_t steps = 250;
  std::vector<simloop::ScenarioConfig> cs;
  std::vector<std::vector<double>> us;
  for (std::uint64_t s = 0; s < 5; ++s) {
    cs.push_back(config(s, steps, s != 3));  // disturbances still apply, except in one baseline
    us.push_back(random_controls(100 + s, steps, nu));
  }
  std::vector<simloop::RunInputs> inputs;
  for (const auto& u : us) inputs.push_back(controls_input(u, steps, nu));
  inputs[4] = inputs[0];  // runs may share one array
  std::vector<simloop::RunRecord> alone;
  for (size_t i = 0; i < cs.size(); ++i) {
    alone.push_back(simloop::run_scenario(scene, scenario, cs[i], nullptr, nullptr, nullptr, inputs[i]));
  }
  EXPECT_FALSE(same(alone[0].final_state, alone[1].final_state));
  for (int threads : {1, 2}) {
    const auto batch = simloop::run_scenario_batch(scene, scenario, cs, threads, nullptr, inputs);
    ASSERT_EQ(batch.size(), cs.size());
    for (size_t i = 0; i < cs.size(); ++i) {
      EXPECT_TRUE(same(batch[i].final_state, alone[i].final_state)) << i << ", " << threads << " threads";
      const simloop::Trajectory& a = batch[i].trajectory;
      const simloop::Trajectory& b = alone[i].trajectory;
      ASSERT_EQ(a.rows(), b.rows());
      EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.rows() * a.columns())), 0);
    }
    // Without rows: the same final rows and states, no trajectory.
    const auto lean = simloop::run_scenario_batch(scene, scenario, cs, threads, nullptr, inputs, false);
    for (size_t i = 0; i < cs.size(); ++i) {
      EXPECT_EQ(lean[i].trajectory.rows(), 0);
      EXPECT_EQ(lean[i].rows, alone[i].rows);
      EXPECT_TRUE(same(lean[i].final_row, alone[i].final_row) ||
                  std::memcmp(lean[i].final_row.data(), alone[i].final_row.data(),
                              sizeof(double) * alone[i].final_row.size()) == 0);
      EXPECT_TRUE(same(lean[i].final_state, alone[i].final_state));
      EXPECT_EQ(simloop::metrics_json(lean[i]), simloop::metrics_json(alone[i]));
    }
  }
}

TEST(BatchControls, AnInitialStateContinuesARunBitForBit) {
  const simloop::Scenario scenario = pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  const int nu = scene.get()->nu;
  const std::vector<double> u = random_controls(3, 600, nu);
  const std::vector<double> first(u.begin(), u.begin() + 300 * nu), second(u.begin() + 300 * nu, u.end());
  const auto whole = simloop::run_scenario(scene, scenario, config(0, 600, false), nullptr, nullptr, nullptr,
                                           controls_input(u, 600, nu));
  const auto half = simloop::run_scenario(scene, scenario, config(0, 300, false), nullptr, nullptr, nullptr,
                                          controls_input(first, 300, nu));
  simloop::RunInputs rest = controls_input(second, 300, nu);
  rest.initial_state = half.final_state.data();
  rest.state_size = half.final_state.size();
  const auto continued = simloop::run_scenario(scene, scenario, config(0, 300, false), nullptr, nullptr, nullptr, rest);
  EXPECT_TRUE(same(continued.final_state, whole.final_state));
  EXPECT_EQ(continued.sim_time, whole.sim_time);  // the state carries the time
  EXPECT_FALSE(same(half.final_state, whole.final_state));
}

TEST(BatchControls, ALeanRunFromAStateIsNeitherResetNorDerivedFirstAndKeepsItsBits) {
  // Without rows kept or observers, a run from a whole state is put in place
  // as it is (no mj_resetData, no forward pass: the first step derives), on
  // a Data other runs used before it: the bits of the same run kept whole.
  const simloop::Scenario scenario = pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  const int nu = scene.get()->nu;
  const std::vector<double> u = random_controls(7, 200, nu);
  const auto half = simloop::run_scenario(scene, scenario, config(0, 150, false), nullptr, nullptr, nullptr,
                                          controls_input(u, 150, nu));
  std::vector<double> later = half.final_state;
  later[0] += 0.25;  // the time
  std::vector<simloop::ScenarioConfig> cs;
  std::vector<simloop::RunInputs> inputs;
  for (std::uint64_t s = 0; s < 4; ++s) {
    cs.push_back(config(s, 200, true));
    inputs.push_back(controls_input(u, 200, nu));
    if (s % 2 == 1) continue;  // from the scene's reset pose, between runs from states
    inputs.back().initial_state = (s == 0 ? half.final_state : later).data();
    inputs.back().state_size = later.size();
  }
  const auto kept = simloop::run_scenario_batch(scene, scenario, cs, 1, nullptr, inputs);
  const auto lean = simloop::run_scenario_batch(scene, scenario, cs, 1, nullptr, inputs, false);
  for (size_t i = 0; i < cs.size(); ++i) {
    EXPECT_TRUE(same(lean[i].final_state, kept[i].final_state)) << i;
    ASSERT_EQ(lean[i].final_row.size(), kept[i].final_row.size());
    EXPECT_EQ(
        std::memcmp(lean[i].final_row.data(), kept[i].final_row.data(), sizeof(double) * kept[i].final_row.size()), 0)
        << i;
    EXPECT_EQ(simloop::metrics_json(lean[i]), simloop::metrics_json(kept[i])) << i;
  }
  EXPECT_FALSE(same(kept[0].final_state, kept[2].final_state));
}

TEST(BatchControls, BadInputsAreRefusedByNameBeforeAnyStep) {
  const simloop::Scenario scenario = pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  const int nu = scene.get()->nu;
  const auto refused = [&](const simloop::RunInputs& in, const std::string& words) {
    try {
      (void)simloop::run_scenario(scene, scenario, config(0, 100, true), nullptr, nullptr, nullptr, in);
      ADD_FAILURE() << "accepted: " << words;
    } catch (const simloop::InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  std::vector<double> u = random_controls(1, 100, nu);
  refused(controls_input(u, 99, nu), "controls must have one row per step and one column per actuator, (100, 2)");
  refused(controls_input(u, 100, nu - 1), "got (100, 1)");
  u[57 * nu + 1] = std::nan("");
  refused(controls_input(u, 100, nu), "controls must be finite, got nan at step 57, actuator 1");
  std::vector<double> state = simloop::get_state(scene.get(), simloop::Data(scene).get());
  simloop::RunInputs in;
  in.initial_state = state.data();
  in.state_size = state.size() + 1;  // (MuJoCo's own state, where there is one, is shorter: state.hpp)
  refused(in, "initial_state must hold " + std::to_string(state.size()) + " values (simloop's state, state_layout)");
  in.state_size = state.size();
  state[3] = INFINITY;
  refused(in, "initial_state must be finite, got inf at index 3");
  // In a batch, the run's index leads.
  std::vector<simloop::ScenarioConfig> cs = {config(0, 100, true), config(1, 100, true)};
  std::vector<double> good = random_controls(1, 100, nu);
  std::vector<simloop::RunInputs> inputs = {controls_input(good, 100, nu), controls_input(good, 50, nu)};
  try {
    (void)simloop::run_scenario_batch(scene, scenario, cs, 1, nullptr, inputs);
    ADD_FAILURE() << "accepted";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("run 1: controls must have", 0), 0u) << e.what();
  }
  inputs.pop_back();
  EXPECT_THROW((void)simloop::run_scenario_batch(scene, scenario, cs, 1, nullptr, inputs), simloop::InvalidArgument);
}

TEST(BatchControls, WholeArraysSplitIntoRunsOrAreSharedAndWrongShapesAreNamed) {
  const std::vector<double> values(3 * 4 * 2, 0.0);
  const simloop::InputArray per_run{values.data(), {3, 4, 2}}, shared{values.data(), {4, 2}};
  const std::vector<simloop::RunInputs> own = simloop::split_inputs(3, true, per_run, std::nullopt);
  ASSERT_EQ(own.size(), 3u);
  EXPECT_EQ(own[2].controls, values.data() + 2 * 4 * 2);
  EXPECT_EQ(own[2].control_steps, 4);
  EXPECT_EQ(own[2].control_width, 2);
  EXPECT_EQ(own[2].initial_state, nullptr);
  const std::vector<simloop::RunInputs> same =
      simloop::split_inputs(3, true, shared, simloop::InputArray{values.data(), {5}});
  EXPECT_EQ(same[2].controls, values.data());
  EXPECT_EQ(same[2].initial_state, values.data());
  EXPECT_EQ(same[2].state_size, 5u);
  const auto refused = [](const std::function<void()>& call, const std::string& message) {
    try {
      call();
      ADD_FAILURE() << "accepted: " << message;
    } catch (const simloop::InvalidArgument& e) {
      EXPECT_EQ(e.what(), message);
    }
  };
  refused([&] { (void)simloop::split_inputs(1, false, per_run, std::nullopt); },
          "controls must be shaped (steps, nu), got shape (3, 4, 2)");
  refused(
      [&] {
        (void)simloop::split_inputs(2, true, simloop::InputArray{values.data(), {24}}, std::nullopt);
      },
      "controls must be shaped (runs, steps, nu) or (steps, nu), got shape (24,)");
  refused([&] { (void)simloop::split_inputs(4, true, per_run, std::nullopt); },
          "controls: 3 runs' controls for 4 runs");
  refused(
      [&] {
        (void)simloop::split_inputs(1, false, std::nullopt, simloop::InputArray{values.data(), {}});
      },
      "initial_state must be shaped (state_size,), got shape ()");
  refused(
      [&] {
        (void)simloop::split_inputs(2, true, std::nullopt, simloop::InputArray{values.data(), {3, 8}});
      },
      "initial_state: 3 states for 2 runs");
}

}  // namespace
