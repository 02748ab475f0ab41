#include <gtest/gtest.h>

#include <limits>

#include "simloop/shove.hpp"

namespace {

// Expected values come from an independent Python implementation of
// MT19937-64 (the reference algorithm, not std::mt19937_64) with the same
// draw rules: newtons = 6 + 6 * ((g() >> 11) * 2^-53), sign from the second draw.
TEST(DrawShove, PinnedSeeds) {
  struct Pin {
    std::uint64_t seed;
    double newtons;
    double sign;
  };
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

TEST(DrawShove, StaysInTheChaptersRange) {
  int negatives = 0;
  for (std::uint64_t seed = 0; seed < 2000; ++seed) {
    const simloop::Shove s = simloop::draw_shove(seed, 10);
    ASSERT_GE(s.newtons, 6.0);
    ASSERT_LT(s.newtons, 12.0);
    negatives += s.sign < 0;
  }
  // Both directions occur, roughly equally.
  EXPECT_GT(negatives, 900);
  EXPECT_LT(negatives, 1100);
}

}  // namespace
