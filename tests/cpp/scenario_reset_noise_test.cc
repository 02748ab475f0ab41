// Reset noise a trainer shapes: a width per coordinate or per joint, and a
// uniform or normal distribution, drawn from the run's seeded generator.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/shove.hpp"
#include "test_util.hpp"

namespace {

using simloop::Scenario;
using test::error_of;

// PushT (nq 9: tblock's free joint, then slide_x, slide_y; nv 8) with a drawn
// disturbance, and `reset` as its [reset] table's body.
Scenario pusht(const std::string& reset) {
  return Scenario::from_toml_string(
      "name = \"pusht-noise\"\nscene = \"pusht.xml\"\nsteps = 10\n"
      "[[disturbance]]\nbody = \"tblock\"\nnewtons = [0.5, 1.5]\ndirection = [0, 1, 0]\n"
      "[reset]\n" +
          reset,
      "pusht-noise", SIMLOOP_TEST_SCENES);
}

const simloop::Model& scene() {
  static const simloop::Model model = simloop::load_scene(pusht(""));
  return model;
}

// The start a seed draws (qpos, qvel), without running it.
simloop::Schedule::Start start(const Scenario& s, std::uint64_t seed) {
  const simloop::ResolvedScenario resolved = simloop::resolve(s, scene().get());
  const auto draws = simloop::make_draws(seed);
  return simloop::build_schedule(resolved, s, scene().timestep(), *draws).start;
}

std::vector<double> qpos0() { return {scene().get()->qpos0, scene().get()->qpos0 + scene().get()->nq}; }

TEST(ResetNoise, StandardNormalHasMeanZeroAndUnitSpread) {
  const auto draws = simloop::make_draws(11);
  double sum = 0.0, squares = 0.0;
  int beyond_two = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double z = simloop::standard_normal(*draws);
    sum += z;
    squares += z * z;
    beyond_two += std::abs(z) > 2.0;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);  // its standard error: 0.0022
  EXPECT_NEAR(squares / n, 1.0, 0.02);
  EXPECT_NEAR(static_cast<double>(beyond_two) / n, 0.0455, 0.004);  // a normal's tails, not a uniform's
}

TEST(ResetNoise, TheSeedDecidesAndAWidthOfZeroLeavesItsCoordinateExact) {
  const Scenario s = pusht("qpos_noise = [0, 0.01, 0, 0, 0, 0, 0, 0.02, 0]\nqvel_noise = {slide_y = 0.3}\n");
  const simloop::Schedule::Start a = start(s, 5), b = start(s, 5), c = start(s, 6);
  EXPECT_EQ(a.qpos, b.qpos);
  EXPECT_EQ(a.qvel, b.qvel);
  EXPECT_NE(a.qpos, c.qpos);
  const std::vector<double> q0 = qpos0();
  for (std::size_t i = 0; i < q0.size(); ++i) {
    if (i == 1 || i == 7) {
      EXPECT_NE(a.qpos[i], q0[i]) << i;
      EXPECT_LE(std::abs(a.qpos[i] - q0[i]), i == 1 ? 0.01 : 0.02) << i;
    } else {
      EXPECT_EQ(a.qpos[i], q0[i]) << i;  // bit for bit
    }
  }
  for (std::size_t i = 0; i < 8; ++i) {
    if (i == 7) {
      EXPECT_NE(a.qvel[i], 0.0);
    } else {
      EXPECT_EQ(a.qvel[i], 0.0) << i;
    }
  }
}

TEST(ResetNoise, AJointsWidthIsItsCoordinatesAndEveryCoordinateIsDrawnInOrder) {
  // By joint or as a list, the same widths draw the same values: one draw per coordinate, in order.
  const Scenario named = pusht("qpos_noise = {slide_x = 0.2}\nqvel_noise = {slide_y = 0.3}\n");
  const Scenario named_listed =
      pusht("qpos_noise = [0, 0, 0, 0, 0, 0, 0, 0.2, 0]\nqvel_noise = [0, 0, 0, 0, 0, 0, 0, 0.3]\n");
  EXPECT_EQ(start(named, 3).qpos, start(named_listed, 3).qpos);
  EXPECT_EQ(start(named, 3).qvel, start(named_listed, 3).qvel);
  // A scalar is that width on every coordinate: the very draws of the list.
  const Scenario scalar = pusht("qpos_noise = 0.1\n");
  const Scenario all = pusht("qpos_noise = [0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1]\n");
  EXPECT_EQ(start(scalar, 4).qpos, start(all, 4).qpos);
}

TEST(ResetNoise, NormalNoiseHasTheGivenStandardDeviation) {
  // HalfCheetah's and Ant's shape: qpos uniform, qvel normal.
  const Scenario s = pusht("qpos_noise = 0.1\nqvel_noise = 0.5\nqvel_noise_distribution = \"normal\"\n");
  double sum = 0.0, squares = 0.0, largest_qpos = 0.0;
  int count = 0, beyond_sigma = 0;
  const std::vector<double> q0 = qpos0();
  for (std::uint64_t seed = 0; seed < 2000; ++seed) {
    const simloop::Schedule::Start st = start(s, seed);
    for (const double v : st.qvel) {
      sum += v;
      squares += v * v;
      beyond_sigma += std::abs(v) > 0.5;
      ++count;
    }
    largest_qpos = std::max(largest_qpos, std::abs(st.qpos[7] - q0[7]));
  }
  EXPECT_NEAR(sum / count, 0.0, 0.02);  // 16,000 draws: standard error 0.004
  EXPECT_NEAR(std::sqrt(squares / count), 0.5, 0.02);
  EXPECT_NEAR(static_cast<double>(beyond_sigma) / count, 0.317, 0.02);  // a uniform of that spread: 0.42
  EXPECT_LE(largest_qpos, 0.1);                                         // qpos stays uniform
  EXPECT_GT(largest_qpos, 0.09);
}

TEST(ResetNoise, OptionsReplaceTheWidthsOrTheDistributionAlone) {
  const Scenario own = pusht("qvel_noise = [0, 0, 0, 0, 0, 0, 0, 0.3]\nqvel_noise_distribution = \"normal\"\n");
  const simloop::ResetSpec wider = simloop::reset_over(own.reset, "[reset]\nqvel_noise = 0.5\n", "options");
  EXPECT_EQ(wider.qvel_noise.distribution, simloop::ResetSpec::Noise::Distribution::kNormal);
  EXPECT_TRUE(wider.qvel_noise.each.empty());
  EXPECT_EQ(wider.qvel_noise.scale, 0.5);
  const simloop::ResetSpec uniform =
      simloop::reset_over(own.reset, "[reset]\nqvel_noise_distribution = \"uniform\"\n", "options");
  EXPECT_EQ(uniform.qvel_noise.distribution, simloop::ResetSpec::Noise::Distribution::kUniform);
  EXPECT_EQ(uniform.qvel_noise.each, own.reset.qvel_noise.each);
}

TEST(ResetNoise, BadNoiseNamesTheKey) {
  const auto file_error = [](const std::string& reset) { return error_of([&] { (void)pusht(reset); }); };
  EXPECT_EQ(file_error("qvel_noise_distribution = \"gauss\"\n"),
            "pusht-noise: reset.qvel_noise_distribution: must be \"uniform\" or \"normal\", got \"gauss\"");
  EXPECT_EQ(file_error("qpos_noise = \"wide\"\n"),
            "pusht-noise: reset.qpos_noise: expected a width, an array of widths (one per coordinate) or a table of "
            "widths by joint name");
  EXPECT_EQ(file_error("qpos_noise = [0.1, -1]\n"),
            "pusht-noise: reset.qpos_noise: must not be negative (a uniform noise's half-width or a normal noise's "
            "standard deviation), got -1.0");
  EXPECT_EQ(file_error("qvel_noise = {slide_x = -2}\n"),
            "pusht-noise: reset.qvel_noise.slide_x: must not be negative (a uniform noise's half-width or a normal "
            "noise's standard deviation), got -2.0");
  const auto resolve_error = [](const std::string& reset) { return error_of([&] { (void)start(pusht(reset), 0); }); };
  EXPECT_EQ(resolve_error("qpos_noise = [0.1, 0.1, 0.1]\n"),
            "reset.qpos_noise must hold the scene's nq = 9 widths (one per coordinate), got 3");
  EXPECT_EQ(resolve_error("qvel_noise = {slidex = 0.1}\n"),
            "reset.qvel_noise: no joint named 'slidex' (did you mean 'slide_x'?); the scene's joints: slide_x, "
            "slide_y; unnamed, by index: 0");
}

}  // namespace
