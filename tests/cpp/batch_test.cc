#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "simloop/batch.hpp"
#include "simloop/errors.hpp"
#include "simloop/output.hpp"
#include "simloop/sim.hpp"

namespace {

using simloop::Trajectory;

const simloop::Model& scene() {
  static const simloop::Model model = simloop::Model::pusher_scene();
  return model;
}

bool same_bits(const Trajectory& a, const Trajectory& b) {
  return a.rows() == b.rows() && a.columns() == b.columns() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.rows()) * static_cast<size_t>(a.columns())) == 0;
}

std::vector<simloop::RunConfig> mixed_configs() {
  std::vector<simloop::RunConfig> configs;
  for (std::uint64_t seed = 0; seed < 6; ++seed) {
    for (double dt : {0.002, 0.01, 0.05}) {
      simloop::RunConfig c;
      c.seed = seed;
      c.timestep = dt;
      c.steps = 300 + 17 * static_cast<std::int64_t>(seed);
      c.perturb = seed % 3 != 0;
      configs.push_back(c);
    }
  }
  return configs;
}

TEST(Batch, EqualsSequentialRunsWhateverTheThreadCount) {
  const auto configs = mixed_configs();
  for (int threads : {1, 2, 3}) {
    const auto batch = simloop::run_batch(scene(), configs, threads);
    ASSERT_EQ(batch.size(), configs.size());
    for (size_t i = 0; i < configs.size(); ++i) {
      const auto single = simloop::run(scene(), configs[i]);
      EXPECT_TRUE(same_bits(batch[i].trajectory, single.trajectory)) << "run " << i << ", " << threads << " threads";
      EXPECT_EQ(simloop::metrics_json(batch[i].metrics), simloop::metrics_json(single.metrics));
      EXPECT_EQ(batch[i].timestep, configs[i].timestep);
    }
  }
}

TEST(Batch, RefusesBadConfigsBeforeRunningAny) {
  auto configs = mixed_configs();
  configs[4].timestep = -1.0;
  try {
    (void)simloop::run_batch(scene(), configs, 2);
    FAIL() << "accepted";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "run 4: timestep must be a positive, finite number of seconds, got -1.0");
  }
  EXPECT_THROW((void)simloop::run_batch(scene(), mixed_configs(), -1), simloop::InvalidArgument);
  EXPECT_TRUE(simloop::run_batch(scene(), {}, 2).empty());
  EXPECT_EQ(simloop::batch_workers(2, 1), 1);
  EXPECT_EQ(simloop::batch_workers(8, 100), 8);
  EXPECT_GE(simloop::batch_workers(0, 100), 1);
}

// Sim's rhythm, written out as the chapter's loop, is the chapter's loop.
TEST(Sim, TheChaptersLoopWrittenWithSimMatchesRun) {
  simloop::RunConfig config;
  config.steps = 600;
  const auto reference = simloop::run(scene(), config);
  simloop::Sim sim(scene());
  const simloop::Shove& shove = reference.shove;
  for (std::int64_t step = 0; step < config.steps; ++step) {
    sim.set_ctrl(1.0);
    if (step == shove.start_step) sim.apply_force({0.0, shove.force_y(), 0.0});
    if (step == shove.start_step + shove.num_steps) sim.clear_force();
    sim.step();
  }
  const std::int64_t last = reference.trajectory.rows() - 1;
  const auto pos = sim.box_position();
  for (int i = 0; i < 3; ++i) EXPECT_EQ(pos[i], reference.trajectory.at(last, Trajectory::kBoxX + i));
  EXPECT_EQ(sim.pusher_x(), reference.trajectory.at(last, Trajectory::kPusherX));
  EXPECT_EQ(sim.time(), reference.sim_time);
  EXPECT_EQ(sim.steps_taken(), 600);
}

TEST(Sim, AnAppliedForcePersistsUntilCleared) {
  simloop::Sim sim(scene());
  sim.apply_force({0.0, 9.0, 0.0});
  sim.step(10);
  EXPECT_EQ(sim.applied_force()[1], 9.0);  // MuJoCo did not clear it
  const double vy_after_10 = sim.box_velocity()[1];
  sim.step(10);
  EXPECT_GT(sim.box_velocity()[1], vy_after_10);  // still pushing: still accelerating
  sim.clear_force();
  EXPECT_EQ(sim.applied_force()[1], 0.0);
  sim.step(200);
  EXPECT_NEAR(sim.box_velocity()[1], 0.0, 1e-3);  // friction stops it once the force is gone
}

TEST(Sim, ReadsContactsAndResets) {
  simloop::Sim sim(scene());
  const auto contacts = sim.contacts();
  ASSERT_FALSE(contacts.empty());
  for (const auto& c : contacts) {
    EXPECT_EQ(c.geom1, "floor");
    EXPECT_TRUE(c.geom2 == "box_geom" || c.geom2 == "pusher_geom") << c.geom2;
  }
  sim.set_ctrl(1.0);
  sim.set_timestep(0.01);
  sim.step(5);
  EXPECT_NEAR(sim.time(), 0.05, 1e-12);
  sim.reset();
  EXPECT_EQ(sim.time(), 0.0);
  EXPECT_EQ(sim.ctrl(), 0.0);
  EXPECT_EQ(sim.box_position()[0], 0.4);
  EXPECT_EQ(sim.timestep(), 0.01);  // the timestep is the model's, kept across reset
  EXPECT_THROW(sim.step(0), simloop::InvalidArgument);
  EXPECT_THROW(sim.set_ctrl(NAN), simloop::InvalidArgument);
  EXPECT_THROW(sim.apply_force({0.0, INFINITY, 0.0}), simloop::InvalidArgument);
  EXPECT_THROW(sim.set_timestep(0.0), simloop::InvalidArgument);
}

TEST(PusherTrack, SlidesAlongXFromItsRestPose) {
  const simloop::PusherTrack track = simloop::pusher_track(scene());
  EXPECT_EQ(track.rest_position, (std::array<double, 3>{0.0, 0.0, 0.05}));
  EXPECT_EQ(track.axis, (std::array<double, 3>{1.0, 0.0, 0.0}));
  EXPECT_EQ(track.q0, 0.0);
}

}  // namespace
