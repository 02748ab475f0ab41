// A policy in the loop (run_schedule's Policy hook) and episodes stepped
// from outside (Episodes): the same bits as the open-loop run when they
// write the same ctrl, and as each other whatever the thread count.
#include "simloop/episode.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "run_detail.hpp"
#include "simloop/errors.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/state.hpp"

namespace {

// PushT with constant controls (so a policy can write exactly what they do)
// and a drawn disturbance.
simloop::Scenario constant_pusht(const char* length = "steps = 700") {
  return simloop::Scenario::from_toml_string(std::string("name = \"pusht-constant\"\nscene = \"pusht.xml\"\n") +
                                                 length +
                                                 "\n[[control]]\nactuator = \"push_x\"\nvalue = 0.8\n"
                                                 "[[control]]\nactuator = \"push_y\"\nvalue = 0.3\n"
                                                 "[[disturbance]]\nbody = \"tblock\"\nnewtons = [0.5, 1.5]\n"
                                                 "direction = [0, 1, 0]\nrandom_sign = true\nstart_step = 300\n"
                                                 "steps = 50\n",
                                             "constant_pusht", SIMLOOP_TEST_SCENES);
}

bool same_bits(const double* a, const double* b, std::size_t n) { return std::memcmp(a, b, n * sizeof(double)) == 0; }

bool same_run(const simloop::RunRecord& a, const simloop::RunRecord& b) {
  const simloop::Trajectory& x = a.trajectory;
  const simloop::Trajectory& y = b.trajectory;
  return x.rows() == y.rows() && x.columns() == y.columns() && a.final_row.size() == b.final_row.size() &&
         same_bits(a.final_row.data(), b.final_row.data(), a.final_row.size()) &&
         same_bits(x.data(), y.data(), static_cast<std::size_t>(x.rows()) * static_cast<std::size_t>(x.columns()));
}

int column(const std::vector<simloop::Column>& columns, const std::string& name) {
  for (std::size_t c = 0; c < columns.size(); ++c) {
    if (columns[c].name == name) return static_cast<int>(c);
  }
  throw std::runtime_error("no column " + name);
}

// Writes fixed values.
class Constant : public simloop::Policy {
 public:
  Constant(std::int64_t every, std::vector<double> ctrl) : Policy(every), ctrl_(std::move(ctrl)) {}
  void decide(std::int64_t, const double*, int, std::vector<double>& ctrl) override {
    std::copy(ctrl_.begin(), ctrl_.begin() + static_cast<std::ptrdiff_t>(ctrl.size()), ctrl.begin());
  }
  int calls = 0;

 private:
  std::vector<double> ctrl_;
};

// Steers the pusher from what it sees, and keeps what it saw and did.
class Steering : public simloop::Policy {
 public:
  Steering(std::int64_t every, int x_column) : Policy(every), x_(x_column) {}
  void decide(std::int64_t step, const double* observation, int width, std::vector<double>& ctrl) override {
    steps.push_back(step);
    observations.emplace_back(observation, observation + width);
    ctrl[0] = std::clamp(4.0 * (0.45 - observation[x_]), -1.0, 1.0);
    ctrl[1] = std::sin(5.0 * observation[1]);
    actions.push_back(ctrl);
  }
  std::vector<std::int64_t> steps;
  std::vector<std::vector<double>> observations, actions;

 private:
  int x_;
};

TEST(Policy, WritingTheScheduledCtrlGivesTheOpenLoopRunsBits) {
  const simloop::Scenario scenario = constant_pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  for (std::uint64_t seed : {0u, 3u}) {
    simloop::ScenarioConfig config;
    config.seed = seed;
    const simloop::RunRecord open = simloop::run_scenario(scene, scenario, config);
    for (std::int64_t every : {1, 7, 50, 5000}) {
      Constant policy(every, {0.8, 0.3});
      const simloop::RunRecord closed = simloop::run_scenario(scene, scenario, config, nullptr, nullptr, nullptr,
                                                              simloop::RunInputs::deciding(policy));
      EXPECT_TRUE(same_run(open, closed)) << "seed " << seed << ", every " << every;
    }
    // And the hook does decide: other values, other bits.
    Constant other(50, {0.8, 0.31});
    EXPECT_FALSE(same_run(open, simloop::run_scenario(scene, scenario, config, nullptr, nullptr, nullptr,
                                                      simloop::RunInputs::deciding(other))));
  }
}

TEST(Policy, DecidesEveryKStepsOnTheRecordersRowAndItsCtrlWinsOverTheSchedules) {
  const simloop::Scenario scenario = constant_pusht("steps = 230");
  const simloop::Model scene = simloop::load_scene(scenario);
  simloop::ScenarioConfig config;
  config.record_every = 1;
  const simloop::RunRecord probe = simloop::run_scenario(scene, scenario, config);
  Steering policy(50, column(probe.columns, "tblock_x"));
  const simloop::RunRecord r =
      simloop::run_scenario(scene, scenario, config, nullptr, nullptr, nullptr, simloop::RunInputs::deciding(policy));
  EXPECT_EQ(policy.steps, (std::vector<std::int64_t>{0, 50, 100, 150, 200}));
  const int ctrl_x = column(r.columns, "push_x_ctrl");
  for (std::size_t k = 0; k < policy.steps.size(); ++k) {
    const std::int64_t step = policy.steps[k];
    const double* row = r.trajectory.row(step);
    // The observation is the row the trajectory records for that step, but
    // for the ctrl and what follows from it (the actuators' force): the row
    // has the new decision's, the observation the one before's.
    for (std::size_t c = 0; c < r.columns.size(); ++c) {
      const std::string& name = r.columns[c].name;
      if (name.size() > 6 &&
          (name.compare(name.size() - 5, 5, "_ctrl") == 0 || name.compare(name.size() - 6, 6, "_force") == 0)) {
        continue;
      }
      EXPECT_TRUE(same_bits(&row[c], &policy.observations[k][c], 1)) << r.columns[c].name << " at step " << step;
    }
    // Held until the next decision; the schedule's 0.8 never shows.
    for (std::int64_t s = step; s < std::min<std::int64_t>(step + 50, 230); ++s) {
      EXPECT_EQ(r.trajectory.at(s, ctrl_x), policy.actions[k][0]) << "step " << s;
    }
    const double before = k == 0 ? 0.0 : policy.actions[k - 1][0];
    EXPECT_EQ(policy.observations[k][static_cast<std::size_t>(ctrl_x)], before);
  }
}

TEST(Policy, ForwardKeepingStateLeavesTheStateBitForBit) {
  // MuJoCo 2.2's mj_forward normalizes the T-block's quaternion in qpos in
  // place (the next mj_step would again: one bit off after 250 steps).
  const simloop::Model scene = simloop::Model::from_file(std::string(SIMLOOP_TEST_SCENES) + "/pusht.xml");
  simloop::Data data(scene);
  const mjModel* m = scene.get();
  mjData* d = data.get();
  d->ctrl[0] = 0.8;
  d->ctrl[1] = 0.3;
  for (int i = 0; i < 250; ++i) mj_step(m, d);
  const std::vector<double> before = simloop::get_state(m, d);
  simloop::forward_keeping_state(m, d);
  EXPECT_TRUE(same_bits(before.data(), simloop::get_state(m, d).data(), before.size()));
}

TEST(Policy, AnExceptionStopsTheRunAndReachesTheCaller) {
  struct Failing : simloop::Policy {
    Failing() : Policy(10) {}
    void decide(std::int64_t step, const double*, int, std::vector<double>&) override {
      if (step == 30) throw std::runtime_error("no idea at 30");
    }
  } policy;
  const simloop::Scenario scenario = constant_pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  simloop::RunControl control;
  EXPECT_THROW((void)simloop::run_scenario(scene, scenario, {}, nullptr, nullptr, &control,
                                           simloop::RunInputs::deciding(policy)),
               std::runtime_error);
  EXPECT_EQ(control.steps_done(), 30);
}

TEST(Policy, ItsCtrlIsCheckedNamingTheDecisionStep) {
  struct Answering : simloop::Policy {
    explicit Answering(std::vector<double> answer) : Policy(10), answer_(std::move(answer)) {}
    void decide(std::int64_t step, const double*, int, std::vector<double>& ctrl) override {
      if (step == 20) ctrl = answer_;
    }
    std::vector<double> answer_;
  };
  const simloop::Scenario scenario = constant_pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  const auto message = [&](std::vector<double> answer) -> std::string {
    Answering policy(std::move(answer));
    try {
      (void)simloop::run_scenario(scene, scenario, {}, nullptr, nullptr, nullptr, simloop::RunInputs::deciding(policy));
    } catch (const simloop::InvalidArgument& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_EQ(message({0.5}), "the policy must return 2 ctrl values, got 1 at decision step 20");
  EXPECT_EQ(message({0.5, 0.5, 0.5}), "the policy must return 2 ctrl values, got 3 at decision step 20");
  EXPECT_EQ(message({0.5, std::nan("")}),
            "the policy returned a ctrl that is not finite at decision step 20: ctrl[1] is nan");
  EXPECT_EQ(message({-HUGE_VAL, 0.0}),
            "the policy returned a ctrl that is not finite at decision step 20: ctrl[0] is -inf");
  EXPECT_EQ(message({0.5, -0.5}), "(no error)");
}

TEST(Policy, ControlEveryIsChecked) {
  EXPECT_THROW(Constant(0, {}), simloop::InvalidArgument);
  EXPECT_THROW(Constant(simloop::kMaxSteps + 1, {}), simloop::InvalidArgument);
  EXPECT_NO_THROW(Constant(simloop::kMaxSteps, {}));
}

TEST(Policy, BatchesEqualSequentialRunsAtAnyThreadCount) {
  const simloop::Scenario scenario = constant_pusht("steps = 300");
  const simloop::Model scene = simloop::load_scene(scenario);
  std::vector<simloop::ScenarioConfig> configs(5);
  for (std::size_t i = 0; i < configs.size(); ++i) configs[i].seed = i;
  configs[4].timestep = 0.001;
  // A stateless policy (Steering keeps what it saw: not for several threads).
  struct Stateless : simloop::Policy {
    Stateless() : Policy(25) {}
    void decide(std::int64_t, const double* o, int, std::vector<double>& ctrl) override {
      ctrl[0] = std::tanh(o[3]);
      ctrl[1] = -std::tanh(o[4]);
    }
  } policy;
  std::vector<simloop::RunRecord> alone;
  for (const auto& c : configs)
    alone.push_back(
        simloop::run_scenario(scene, scenario, c, nullptr, nullptr, nullptr, simloop::RunInputs::deciding(policy)));
  for (int threads : {1, 2}) {
    const auto batch = simloop::run_scenario_batch(
        scene, scenario, configs, threads, nullptr,
        std::vector<simloop::RunInputs>(configs.size(), simloop::RunInputs::deciding(policy)));
    for (std::size_t i = 0; i < configs.size(); ++i) EXPECT_TRUE(same_run(batch[i], alone[i])) << i << ", " << threads;
  }
}

TEST(Episodes, FollowTheBitsOfAPolicyRunGivenItsActions) {
  const simloop::Scenario scenario = constant_pusht("steps = 230");
  const simloop::Model scene = simloop::load_scene(scenario);
  simloop::ScenarioConfig config;
  config.seed = 5;
  simloop::Episodes episodes(scene, scenario, config, 1);
  ASSERT_EQ(episodes.steps(), 230);
  Steering policy(50, column(episodes.columns(), "tblock_x"));
  const simloop::RunRecord r =
      simloop::run_scenario(scene, scenario, config, nullptr, nullptr, nullptr, simloop::RunInputs::deciding(policy));
  const auto width = static_cast<std::size_t>(episodes.width());
  ASSERT_EQ(width, r.columns.size());
  std::vector<double> observation(width);
  episodes.reset(0, 5, observation.data());
  std::uint8_t terminated = 9, truncated = 9;
  for (std::size_t k = 0; k < policy.steps.size(); ++k) {
    EXPECT_TRUE(same_bits(observation.data(), policy.observations[k].data(), width)) << "decision " << k;
    episodes.step(policy.actions[k].data(), policy.actions[k].size(), 50, nullptr, 0, observation.data(), &terminated,
                  &truncated);
    EXPECT_EQ(terminated, 0);
    EXPECT_EQ(truncated, k + 1 == policy.steps.size() ? 1 : 0) << "decision " << k;
  }
  EXPECT_EQ(episodes.steps_taken(0), 230);  // the last call took 30 steps, not 50
  // The end state: every column MuJoCo computes, as the run's final row.
  for (std::size_t c = 0; c < width; ++c) {
    if (!r.columns[c].input) EXPECT_TRUE(same_bits(&observation[c], &r.final_row[c], 1)) << r.columns[c].name;
  }
  EXPECT_THROW(episodes.step(policy.actions[0].data(), policy.actions[0].size(), 50, nullptr, 0, observation.data(),
                             &terminated, &truncated),
               simloop::InvalidArgument);  // ended: reset first
}

TEST(Episodes, ManyAtOnceEqualEachAloneWhateverTheThreadCount) {
  const simloop::Scenario scenario = constant_pusht("steps = 400");
  const simloop::Model scene = simloop::load_scene(scenario);
  const std::size_t n = 6;
  const auto actions_at = [](std::size_t call, std::size_t i) {
    return std::vector<double>{std::sin(0.7 * static_cast<double>(call) + static_cast<double>(i)),
                               std::cos(0.3 * static_cast<double>(call * i))};
  };
  std::vector<std::vector<double>> alone_obs;
  for (std::size_t i = 0; i < n; ++i) {
    simloop::Episodes one(scene, scenario, {}, 1);
    std::vector<double> o(static_cast<std::size_t>(one.width()));
    std::uint8_t term = 0, trunc = 0;
    one.reset(0, 100 + i, o.data());
    for (std::size_t call = 0; call < 5; ++call)
      one.step(actions_at(call, i).data(), 2, 37, nullptr, 0, o.data(), &term, &trunc);
    alone_obs.push_back(o);
  }
  for (int threads : {1, 2, 4}) {
    simloop::Episodes many(scene, scenario, {}, n);
    const auto width = static_cast<std::size_t>(many.width());
    std::vector<double> obs(n * width);
    for (std::size_t i = 0; i < n; ++i) many.reset(i, 100 + i, obs.data() + i * width);
    std::vector<std::uint8_t> term(n), trunc(n);
    for (std::size_t call = 0; call < 5; ++call) {
      std::vector<double> actions;
      for (std::size_t i = 0; i < n; ++i) {
        const auto a = actions_at(call, i);
        actions.insert(actions.end(), a.begin(), a.end());
      }
      many.step(actions.data(), actions.size(), 37, nullptr, 0, obs.data(), term.data(), trunc.data(), threads);
    }
    for (std::size_t i = 0; i < n; ++i) {
      EXPECT_TRUE(same_bits(obs.data() + i * width, alone_obs[i].data(), width)) << i << ", " << threads << " threads";
    }
  }
}

TEST(Episodes, KeepTheirThreadsFromCallToCallThroughAForkAndAThreadLimit) {
  const simloop::Scenario scenario = constant_pusht("steps = 400");
  const simloop::Model scene = simloop::load_scene(scenario);
  const std::size_t n = 4;
  // Six calls at the given thread counts, then the observations.
  const auto stepped = [&](simloop::Episodes& e, const std::vector<int>& threads) {
    const auto width = static_cast<std::size_t>(e.width());
    std::vector<double> obs(n * width);
    std::vector<std::uint8_t> term(n), trunc(n);
    for (std::size_t call = 0; call < threads.size(); ++call) {
      std::vector<double> actions;
      for (std::size_t i = 0; i < 2 * n; ++i) actions.push_back(std::sin(0.3 * static_cast<double>(call * 7 + i)));
      e.step(actions.data(), actions.size(), 11, nullptr, 0, obs.data(), term.data(), trunc.data(), threads[call]);
    }
    return obs;
  };
  const auto started = [&] {
    auto e = std::make_unique<simloop::Episodes>(scene, scenario, simloop::ScenarioConfig{}, n);
    std::vector<double> obs(n * static_cast<std::size_t>(e->width()));
    for (std::size_t i = 0; i < n; ++i) e->reset(i, 40 + i, obs.data() + i * static_cast<std::size_t>(e->width()));
    return e;
  };
  const std::vector<double> alone = stepped(*started(), {1, 1, 1, 1, 1, 1});
  // The kept threads grow and shrink with the count asked for.
  auto kept = started();
  const auto same = [](const std::vector<double>& a, const std::vector<double>& b) {
    return a.size() == b.size() && same_bits(a.data(), b.data(), a.size());
  };
  EXPECT_TRUE(same(stepped(*kept, {2, 4, 1, 2, 3, 4}), alone));
  // A forked child has none of the parent's threads: its own start.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    auto again = started();
    _exit(same(stepped(*again, {2, 2, 4, 1, 2, 2}), alone) && stepped(*kept, {2}).size() == alone.size() ? 0 : 1);
  }
  int status = -1;
  for (int waited = 0; waited < 1000 && waitpid(child, &status, WNOHANG) == 0; ++waited) usleep(10000);
  if (status == -1) {
    kill(child, SIGKILL);
    waitpid(child, &status, 0);
  }
  ASSERT_TRUE(WIFEXITED(status)) << "the forked child hung or crashed";
  EXPECT_EQ(WEXITSTATUS(status), 0);
  // Without threads to be had, the calling thread does it all.
  simloop::detail::limit_thread_starts_for_testing(0);
  auto limited = started();
  const std::vector<double> alone_again = stepped(*limited, {2, 2, 2, 2, 2, 2});
  simloop::detail::limit_thread_starts_for_testing(-1);
  EXPECT_TRUE(same(alone_again, alone));
}

TEST(Episodes, InactiveOnesStayWhereTheyAre) {
  const simloop::Scenario scenario = constant_pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  simloop::Episodes e(scene, scenario, {}, 2);
  const auto width = static_cast<std::size_t>(e.width());
  std::vector<double> obs(2 * width, -1.0);
  e.reset(0, 1, obs.data());
  e.reset(1, 1, obs.data() + width);
  const std::vector<double> actions = {0.5, 0.5, 0.5, 0.5};
  const std::uint8_t active[] = {1, 0};
  std::uint8_t term[2] = {7, 7}, trunc[2] = {7, 7};
  e.step(actions.data(), actions.size(), 20, active, 2, obs.data(), term, trunc);
  EXPECT_EQ(e.steps_taken(0), 20);
  EXPECT_EQ(e.steps_taken(1), 0);
  EXPECT_EQ(term[1], 7);
  EXPECT_FALSE(same_bits(obs.data(), obs.data() + width, width));
}

TEST(Episodes, BadInputIsRefusedBeforeAnyStep) {
  const simloop::Scenario scenario = constant_pusht();
  const simloop::Model scene = simloop::load_scene(scenario);
  simloop::Episodes e(scene, scenario, {}, 2);
  std::vector<double> obs(2 * static_cast<std::size_t>(e.width()));
  std::uint8_t term[2], trunc[2];
  std::vector<double> actions = {0.5, 0.5, 0.5, 0.5};
  e.reset(0, 1, obs.data());
  EXPECT_THROW(e.step(actions.data(), 4, 10, nullptr, 0, obs.data(), term, trunc),
               simloop::InvalidArgument);  // 1 not reset
  e.reset(1, 1, obs.data());
  actions[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(e.step(actions.data(), 4, 10, nullptr, 0, obs.data(), term, trunc), simloop::InvalidArgument);
  actions[3] = 0.0;
  EXPECT_THROW(e.step(actions.data(), 4, 0, nullptr, 0, obs.data(), term, trunc), simloop::InvalidArgument);
  const auto message_of = [&](std::size_t action_count, const std::uint8_t* active, std::size_t active_count) {
    try {
      e.step(actions.data(), action_count, 10, active, active_count, obs.data(), term, trunc);
    } catch (const simloop::InvalidArgument& error) {
      return std::string(error.what());
    }
    return std::string("(no InvalidArgument)");
  };
  const std::uint8_t both[] = {1, 1};
  EXPECT_EQ(message_of(3, nullptr, 0), "actions must hold 2 x 2 values, got 3");
  EXPECT_EQ(message_of(4, both, 1), "active must hold 2 flags");
  EXPECT_EQ(e.steps_taken(0), 0);
  EXPECT_THROW(e.reset(2, 0, obs.data()), simloop::InvalidArgument);
}

TEST(Episodes, ADivergingEpisodeTerminates) {
  // The chapter's scene at 1 s a step: the box goes through the floor.
  const simloop::Scenario scenario = simloop::Scenario::chapter();
  const simloop::Model scene = simloop::load_scene(scenario);
  simloop::ScenarioConfig config;
  config.timestep = 1.0;
  config.steps = 400;
  simloop::Episodes e(scene, scenario, config, 1);
  std::vector<double> obs(static_cast<std::size_t>(e.width()));
  e.reset(0, 0, obs.data());
  const double action = 1.0;
  std::uint8_t term = 0, trunc = 0;
  while (!term && !trunc) e.step(&action, 1, 10, nullptr, 0, obs.data(), &term, &trunc);
  EXPECT_EQ(term, 1);
  EXPECT_EQ(trunc, 0);
  EXPECT_LT(e.steps_taken(0), 400);
  const auto warnings = e.warnings(0);
  ASSERT_FALSE(warnings.empty());
  EXPECT_EQ(warnings.back().first_step + 1, e.steps_taken(0));  // it stopped at the step that diverged
}

}  // namespace
