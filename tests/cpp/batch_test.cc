// run_batch: many runs of the chapter's over one model, the same bits as
// running each alone, whatever the thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "simloop/chapter_scene.hpp"
#include "worker_pool.hpp"
#include "simloop/batch.hpp"
#include "simloop/errors.hpp"
#include "simloop/output.hpp"

namespace {

using simloop::Trajectory;

const simloop::Model& scene() {
  static const simloop::Model model = simloop::pusher_scene();
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

}  // namespace

TEST(WorkerPool, WakesItsThreadsForAShortRoundOnlyWhileTheyAreWarm) {
  // Rounds of no work. Right after a round the threads are still warm (a
  // second round wakes them); after a pause of 5 ms a round this short runs
  // on the calling thread alone. (A machine busy enough to stall a round for
  // milliseconds makes it look long: some tries may wake the threads.)
  simloop::detail::WorkerPool pool;
  std::atomic<int> ran{0};
  const std::function<void(int)> task = [&ran](int) { ran.fetch_add(1); };
  const auto round = [&] {
    const int helpers = pool.start_round(1, task);
    pool.wait_round([] {});
    return helpers;
  };
  EXPECT_EQ(round(), 1) << "the first round starts its thread";
  int warm = 0, alone = 0;
  for (int tries = 0; tries < 5; ++tries) {
    warm += round();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    alone += round() == 0 ? 1 : 0;
  }
  EXPECT_GE(warm, 3);
  EXPECT_GE(alone, 3);
  EXPECT_EQ(ran.load(), 1 + warm + (5 - alone));
}
