// run_batch: many runs of the chapter's over one model, the same bits as
// running each alone, whatever the thread count.
#include "simloop/batch.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <thread>
#include <vector>

#include "chapter_detail.hpp"
#include "simloop/chapter_scene.hpp"
#include "simloop/errors.hpp"
#include "simloop/output.hpp"
#include "worker_pool.hpp"

namespace {

using simloop::Trajectory;

const simloop::Model& scene() {
  static const simloop::Model model = simloop::pusher_scene();
  return model;
}

bool same_bits(const Trajectory& a, const Trajectory& b) {
  return a.rows() == b.rows() && a.columns() == b.columns() &&
         std::memcmp(a.data(), b.data(),
                     sizeof(double) * static_cast<size_t>(a.rows()) * static_cast<size_t>(a.columns())) == 0;
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
    const auto batch = simloop::detail::run_chapter_batch(scene(), configs, {}, threads);
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
    (void)simloop::detail::run_chapter_batch(scene(), configs, {}, 2);
    FAIL() << "accepted";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "run 4: timestep must be a positive, finite number of seconds, got -1.0");
  }
  EXPECT_THROW((void)simloop::detail::run_chapter_batch(scene(), mixed_configs(), {}, -1), simloop::InvalidArgument);
  EXPECT_TRUE(simloop::detail::run_chapter_batch(scene(), {}, {}, 2).empty());
  EXPECT_EQ(simloop::batch_workers(2, 1), 1);
  EXPECT_EQ(simloop::batch_workers(8, 100), 8);
  EXPECT_GE(simloop::batch_workers(0, 100), 1);
}

}  // namespace

TEST(WorkerPool, EachSeatRunsAtMostOnceAndNoneAfterItsRound) {
  // The calling thread's share is nothing after a pause (the threads are
  // asleep: one still waking when wait_round begins loses its seat), and a
  // wait for one seat taken otherwise. Each seat's task runs at most once,
  // as worker 1 .. 3, and none after wait_round returns (its std::function
  // is gone by then: the sanitizers' build would catch a call).
  simloop::detail::WorkerPool pool;
  constexpr int kRounds = 40;
  std::vector<std::array<std::atomic<int>, 4>> ran(kRounds);  // [0]: a worker number out of range
  for (int round = 0; round < kRounds; ++round) {
    auto& counts = ran[static_cast<std::size_t>(round)];
    for (auto& r : counts) r.store(0);
    const std::function<void(int)> task = [&counts](int worker) {
      counts[worker >= 1 && worker <= 3 ? worker : 0].fetch_add(1);
    };
    EXPECT_EQ(pool.start_round(3, task), 3);
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::milliseconds(200);
    while (round % 2 == 1 && std::chrono::steady_clock::now() < give_up && counts[1] + counts[2] + counts[3] == 0) {
      std::this_thread::yield();
    }
    pool.wait_round([] {});
    std::this_thread::sleep_for(std::chrono::microseconds(round % 2 == 0 ? 2000 : 0));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(5));  // for any task that would run late
  int taken = 0;
  for (const auto& r : ran) {
    EXPECT_EQ(r[0].load(), 0);
    for (int w = 1; w <= 3; ++w) {
      EXPECT_LE(r[w].load(), 1);
      taken += r[w].load();
    }
  }
  EXPECT_GT(taken, 0) << "the threads take seats too";
}
