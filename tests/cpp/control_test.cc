// Stopping and watching long work (RunControl), and rows streamed to a sink.
#include "simloop/control.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <vector>

#include "chapter_detail.hpp"
#include "simloop/batch.hpp"
#include "simloop/call_gate.hpp"
#include "simloop/errors.hpp"
#include "simloop/run.hpp"
#include "simloop/sim.hpp"
#include "simloop/sweep.hpp"

namespace {

const simloop::Model& scene() {
  static const simloop::Model model = simloop::pusher_scene();
  return model;
}

// A sink that keeps what it is given, to compare with the kept trajectory.
class CollectRows final : public simloop::RowSink {
 public:
  void start(int columns, std::int64_t rows) override {
    columns_ = columns;
    announced = rows;
  }
  void write(const double* rows, std::int64_t count) override {
    values.insert(values.end(), rows, rows + count * columns_);
    ++blocks;
  }
  int columns_ = 0;
  std::int64_t announced = -1;
  int blocks = 0;
  std::vector<double> values;
};

TEST(RowSink, GetsTheSameRowsTheResultWouldKeep) {
  for (bool audit : {false, true}) {
    for (std::int64_t every : {1, 3, 64, 65, 5000}) {
      simloop::RunConfig config;
      config.steps = 1000;
      config.record_every = every;
      config.audit_energy = audit;
      const simloop::RunResult kept = simloop::run(scene(), config);
      simloop::Data data(scene());
      CollectRows sink;
      const simloop::RunResult streamed = simloop::run(scene(), config, data, &sink);
      EXPECT_EQ(streamed.trajectory.rows(), 0);
      EXPECT_EQ(streamed.rows, kept.rows);
      EXPECT_EQ(sink.announced, kept.trajectory.rows());
      ASSERT_EQ(sink.values.size(), static_cast<size_t>(kept.trajectory.rows() * kept.trajectory.columns()));
      EXPECT_EQ(std::memcmp(sink.values.data(), kept.trajectory.data(), sink.values.size() * sizeof(double)), 0)
          << "audit " << audit << " every " << every;
      // Rows arrive in blocks as the loop goes, not all at the end.
      if (every == 1) EXPECT_GT(sink.blocks, 10);
    }
  }
}

TEST(RowSink, AThrowingSinkStopsTheRunAndTheErrorReachesTheCaller) {
  class Full final : public simloop::RowSink {
   public:
    void start(int, std::int64_t) override {}
    void write(const double*, std::int64_t) override {
      if (++writes == 3) throw simloop::IoError("disk full");
    }
    int writes = 0;
  } sink;
  simloop::RunConfig config;
  simloop::Data data(scene());
  EXPECT_THROW((void)simloop::run(scene(), config, data, &sink), simloop::IoError);
  EXPECT_EQ(sink.writes, 3);
}

TEST(RunControl, PollIsCalledAndCanStopARun) {
  simloop::RunConfig config;
  config.steps = 10'000'000;  // about a minute if nothing stopped it
  int polls = 0;
  std::int64_t last_done = -1, total = 0;
  simloop::RunControl control([&](std::int64_t done, std::int64_t all) {
    ++polls;
    EXPECT_GT(done, last_done);
    last_done = done;
    total = all;
    if (polls == 3) control.request_stop();
  });
  simloop::Data data(scene());
  EXPECT_THROW((void)simloop::run(scene(), config, data, nullptr, &control), simloop::Interrupted);
  EXPECT_EQ(polls, 3);
  EXPECT_EQ(total, config.steps);
  EXPECT_LT(control.steps_done(), config.steps / 10);
}

TEST(RunControl, AStopRequestedBeforehandStopsAtTheFirstChunk) {
  simloop::RunControl control;
  control.request_stop();
  simloop::RunConfig config;
  simloop::Data data(scene());
  EXPECT_THROW((void)simloop::run(scene(), config, data, nullptr, &control), simloop::Interrupted);
  EXPECT_EQ(control.steps_done(), simloop::RunControl::kChunkSteps);

  simloop::Sim sim(scene());
  EXPECT_THROW(sim.step(1000, &control), simloop::Interrupted);
  EXPECT_EQ(sim.steps_taken(), simloop::RunControl::kChunkSteps);
}

TEST(RunControl, StopsABatchAndASweepOnEveryWorker) {
  std::vector<simloop::RunConfig> configs(8);
  for (auto& c : configs) c.steps = 5'000'000;
  int polls = 0;
  simloop::RunControl control([&](std::int64_t, std::int64_t) {
    if (++polls == 2) control.request_stop();
  });
  EXPECT_THROW((void)simloop::detail::run_chapter_batch(scene(), configs, {}, 2, &control), simloop::Interrupted);
  EXPECT_LT(control.steps_done(), 1'000'000);

  int sweep_polls = 0;
  simloop::RunControl sweep_control([&](std::int64_t, std::int64_t) {
    if (++sweep_polls == 2) sweep_control.request_stop();
  });
  EXPECT_THROW((void)simloop::sweep(scene(), {1e-5, 2e-5}, 100.0, 2, &sweep_control), simloop::Interrupted);
}

TEST(RunControl, CountsProgressOverABatch) {
  std::vector<simloop::RunConfig> configs(5);
  for (auto& c : configs) c.steps = 700;
  simloop::RunControl control;
  const auto results = simloop::detail::run_chapter_batch(scene(), configs, {}, 2, &control);
  EXPECT_EQ(results.size(), 5u);
  EXPECT_EQ(control.steps_total(), 3500);
  EXPECT_EQ(control.steps_done(), 3500);
}

// What the poll throws (Python's KeyboardInterrupt, a progress callback's
// error) stops the work at its next chunk, and run() hands it to the
// caller in place of the loop's Interrupted; one run or a batch.
TEST(RunControl, WhatThePollThrowsReachesTheCallerOfRun) {
  struct FromThePoll : std::runtime_error {
    using std::runtime_error::runtime_error;
  };
  simloop::RunConfig config;
  config.steps = 10'000'000;
  config.record_every = 10'000;  // no trajectory to allocate
  int polls = 0;
  simloop::RunControl control([&](std::int64_t, std::int64_t) {
    if (++polls == 2) throw FromThePoll("pressed Ctrl-C");
  });
  simloop::Data data(scene());
  EXPECT_THROW(control.run([&](simloop::RunControl* c) { return simloop::run(scene(), config, data, nullptr, c); }),
               FromThePoll);
  EXPECT_EQ(polls, 2);  // not polled again once stopped
  EXPECT_LT(control.steps_done(), config.steps / 10);
  // Without run(), the loop's own Interrupted; the failure was handed over once.
  EXPECT_THROW(control.run([&](simloop::RunControl* c) { return simloop::run(scene(), config, data, nullptr, c); }),
               simloop::Interrupted);

  std::vector<simloop::RunConfig> configs(4, config);
  simloop::RunControl batch_control([&](std::int64_t, std::int64_t) { throw FromThePoll("progress failed"); });
  EXPECT_THROW(batch_control.run([&](simloop::RunControl* c) {
    return simloop::detail::run_chapter_batch(scene(), configs, {}, 2, c);
  }),
               FromThePoll);
  // Work that fails on its own keeps its own exception.
  simloop::RunControl quiet;
  EXPECT_THROW(quiet.run([](simloop::RunControl*) -> int { throw std::logic_error("the work's own"); }),
               std::logic_error);
}

TEST(CallGate, RefusesReentryOnItsThreadAndMakesOthersWaitInSlices) {
  simloop::CallGate gate;
  const auto no_wait = [](const simloop::CallGate::TryFor&) { FAIL() << "the gate was free"; };
  gate.enter("this Sim is", no_wait);
  try {
    gate.enter("this Sim is", no_wait);
    ADD_FAILURE() << "entered twice on one thread";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_STREQ(e.what(),
                 "this Sim is in the middle of a call on this thread (a signal handler or progress callback called "
                 "it); call it after that call returns");
  }
  // Another thread waits, slice by slice, until the gate is left; a wait
  // that gives up (Ctrl-C between slices) leaves it unentered.
  std::atomic<int> slices{0};
  std::atomic<bool> entered{false};
  std::thread waiter([&] {
    try {
      gate.enter("this Sim is", [&](const simloop::CallGate::TryFor& try_for) {
        simloop::wait_in_slices(try_for, [&] {
          if (++slices == 1000) throw std::runtime_error("gave up");
        });
      });
      entered = true;
      gate.leave();
    } catch (const std::runtime_error&) {
    }
  });
  while (slices < 2) std::this_thread::yield();
  EXPECT_FALSE(entered);
  gate.leave();
  waiter.join();
  EXPECT_TRUE(entered);
  EXPECT_LT(slices, 1000);
  gate.enter("this Sim is", no_wait);  // free again, and re-enterable after leave()
  gate.leave();
}

TEST(CallGate, WaitInSlicesStopsAtItsTimeoutAndWithWhatBetweenThrows) {
  int betweens = 0;
  const auto sleeps = [](std::chrono::milliseconds slice) {
    std::this_thread::sleep_for(slice);
    return false;
  };
  EXPECT_FALSE(simloop::wait_in_slices(
      sleeps, [&] { ++betweens; }, 0.05));
  EXPECT_GE(betweens, 1);
  EXPECT_TRUE(simloop::wait_in_slices([](std::chrono::milliseconds) { return true; }, [] { FAIL(); }, 0.0));
  EXPECT_THROW(simloop::wait_in_slices([](std::chrono::milliseconds) { return false; },
                                       [] { throw std::runtime_error("Ctrl-C"); }),
               std::runtime_error);
}

}  // namespace
