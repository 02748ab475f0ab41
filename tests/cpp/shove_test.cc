#include "simloop/shove.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "simloop/errors.hpp"
#include "simloop/rows.hpp"

namespace {

struct Pin {
  std::uint64_t seed;
  double newtons;
  double sign;
};

// Expected values come from an independent Python implementation of
// MT19937-64 (the reference algorithm, not std::mt19937_64) with the same
// draw rules: newtons = 6 + 6 * ((g() >> 11) * 2^-53), sign from the second draw.
TEST(DrawShove, PinnedSeeds) {
  const Pin pins[] = {
      {0, 6.9587601802227645, 1.0},
      {1, 6.803259864075196, -1.0},
      {2, 11.421624157163965, 1.0},
      {42, 10.530933197727233, 1.0},
      {std::numeric_limits<std::uint64_t>::max(), 6.155483178059423, 1.0},
  };
  for (const Pin& pin : pins) {
    const simloop::Shove s = simloop::draw_shove(pin.seed, 2000);
    EXPECT_EQ(s.newtons, pin.newtons) << "seed " << pin.seed;
    EXPECT_EQ(s.sign, pin.sign) << "seed " << pin.seed;
  }
}

// The chapter's draws, np.random.default_rng(seed): uniform(6.0, 12.0), then
// choice([-1.0, 1.0]). Expected values are numpy's own (numpy 2.x; PCG64 and
// SeedSequence streams are stable across numpy versions); pytest compares
// against numpy over thousands of seeds (tests/python/test_shove_rng.py).
TEST(DrawShove, NumpyPinnedSeeds) {
  const Pin pins[] = {
      {0, 9.821770123928726, 1.0},
      {1, 9.07092974820154, 1.0},
      {2, 7.569672805495898, -1.0},
      {3, 6.513895002861746, -1.0},
  };
  for (const Pin& pin : pins) {
    const simloop::Shove s = simloop::draw_shove(pin.seed, 2000, simloop::ShoveRng::kNumpy);
    EXPECT_EQ(s.newtons, pin.newtons) << "seed " << pin.seed;
    EXPECT_EQ(s.sign, pin.sign) << "seed " << pin.seed;
    EXPECT_EQ(s.rng, simloop::ShoveRng::kNumpy);
    EXPECT_EQ(s.start_step, 1000);
  }
  // The default is still std::mt19937_64.
  EXPECT_EQ(simloop::draw_shove(0, 2000).rng, simloop::ShoveRng::kMt19937_64);
  EXPECT_EQ(simloop::draw_shove(0, 2000).newtons, 6.9587601802227645);
}

TEST(DrawShove, GeneratorNames) {
  EXPECT_EQ(simloop::rng_name(simloop::ShoveRng::kMt19937_64), "mt19937_64");
  EXPECT_EQ(simloop::rng_name(simloop::ShoveRng::kNumpy), "numpy");
  EXPECT_EQ(simloop::parse_rng("numpy"), simloop::ShoveRng::kNumpy);
  EXPECT_EQ(simloop::parse_rng("mt19937_64"), simloop::ShoveRng::kMt19937_64);
  EXPECT_FALSE(simloop::parse_rng("pcg64").has_value());
  EXPECT_EQ(simloop::rng_named("numpy"), simloop::ShoveRng::kNumpy);
  try {
    (void)simloop::rng_named("pcg64");
    FAIL() << "pcg64 was taken";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "rng must be 'mt19937_64' or 'numpy', got 'pcg64'");
  }
  EXPECT_FALSE(simloop::parse_rng("").has_value());
}

TEST(DrawShove, ScheduleFollowsTheChapter) {
  const simloop::Shove s = simloop::draw_shove(0, 2000);
  EXPECT_EQ(s.start_step, 1000);
  EXPECT_EQ(s.num_steps, 50);
  EXPECT_FALSE(s.acts_at(999));
  EXPECT_TRUE(s.acts_at(1000));
  EXPECT_TRUE(s.acts_at(1049));
  EXPECT_FALSE(s.acts_at(1050));
  EXPECT_EQ(s.force_y(), s.sign * s.newtons);
  EXPECT_EQ(simloop::draw_shove(0, 301).start_step, 150);
  EXPECT_EQ(simloop::draw_shove(0, 1).start_step, 0);
}

TEST(DrawShove, TakesARunsSteps) {
  try {
    (void)simloop::draw_shove(0, 0);
    FAIL() << "steps=0 was taken";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "steps must be from 1 to 4611686018427387903, got 0");
  }
  EXPECT_THROW((void)simloop::draw_shove(0, simloop::kMaxSteps + 1), simloop::InvalidArgument);
  EXPECT_EQ(simloop::draw_shove(0, simloop::kMaxSteps).start_step, simloop::kMaxSteps / 2);
}

TEST(DrawShove, StaysInTheChaptersRange) {
  for (const simloop::ShoveRng rng : {simloop::ShoveRng::kMt19937_64, simloop::ShoveRng::kNumpy}) {
    int negatives = 0;
    for (std::uint64_t seed = 0; seed < 2000; ++seed) {
      const simloop::Shove s = simloop::draw_shove(seed, 10, rng);
      ASSERT_GE(s.newtons, 6.0);
      ASSERT_LT(s.newtons, 12.0);
      negatives += s.sign < 0;
    }
    // Both directions occur, roughly equally.
    EXPECT_GT(negatives, 900) << simloop::rng_name(rng);
    EXPECT_LT(negatives, 1100) << simloop::rng_name(rng);
  }
}

}  // namespace
