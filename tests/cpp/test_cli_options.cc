#include <gtest/gtest.h>

#include <initializer_list>
#include <vector>

#include "cli_options.hpp"

namespace {

simloop::cli::Options parse(std::initializer_list<const char*> args) {
  std::vector<const char*> argv = {"sim_loop"};
  argv.insert(argv.end(), args);
  return simloop::cli::parse(static_cast<int>(argv.size()), argv.data());
}

std::string usage_error(std::initializer_list<const char*> args) {
  try {
    (void)parse(args);
  } catch (const simloop::cli::UsageError& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted";
  return {};
}

TEST(CliOptions, DefaultsAreTheChapters) {
  const auto o = parse({});
  EXPECT_EQ(o.run.seed, 0u);
  EXPECT_EQ(o.run.steps, 2000);
  EXPECT_EQ(o.run.timestep, 0.002);
  EXPECT_TRUE(o.run.perturb);
  EXPECT_FALSE(o.run.smoke);
  EXPECT_EQ(o.run.record_every, 1);
  EXPECT_EQ(o.out, "outputs/ch0.1-sim-loop");
  EXPECT_TRUE(o.rerun);
  EXPECT_TRUE(o.model_path.empty());
  EXPECT_EQ(o.run.rng, simloop::ShoveRng::kMt19937_64);
}

TEST(CliOptions, RngPicksTheShovesGenerator) {
  EXPECT_EQ(parse({"--rng", "numpy"}).run.rng, simloop::ShoveRng::kNumpy);
  EXPECT_EQ(parse({"--rng=numpy"}).run.rng, simloop::ShoveRng::kNumpy);
  EXPECT_EQ(parse({"--rng", "numpy", "--rng", "mt19937_64"}).run.rng, simloop::ShoveRng::kMt19937_64);
}

TEST(CliOptions, ParsesEveryFlagInBothSpellings) {
  const auto o = parse({"--seed", "18446744073709551615", "--steps=10", "--timestep", "0.05", "--smoke",
                        "--out=o", "--no-perturb", "--no-rerun", "--record-every", "5", "--model", "m.xml"});
  EXPECT_EQ(o.run.seed, 18446744073709551615u);
  EXPECT_EQ(o.run.steps, 10);
  EXPECT_EQ(o.run.num_steps(), 300);  // --smoke wins
  EXPECT_EQ(o.run.timestep, 0.05);
  EXPECT_FALSE(o.run.perturb);
  EXPECT_FALSE(o.rerun);
  EXPECT_EQ(o.run.record_every, 5);
  EXPECT_EQ(o.out, "o");
  EXPECT_EQ(o.model_path, "m.xml");
  EXPECT_TRUE(parse({"--no-rerun", "--rerun"}).rerun);
  EXPECT_TRUE(parse({"--help"}).help);
  EXPECT_TRUE(parse({"--version"}).version);
}

TEST(CliOptions, BadValuesNameTheFlagAndTheValue) {
  EXPECT_EQ(usage_error({"--timestep", "0"}), "--timestep must be a positive, finite number of seconds, got '0'");
  EXPECT_EQ(usage_error({"--timestep", "-0.002"}),
            "--timestep must be a positive, finite number of seconds, got '-0.002'");
  EXPECT_EQ(usage_error({"--timestep=nan"}), "--timestep must be a positive, finite number of seconds, got 'nan'");
  EXPECT_EQ(usage_error({"--timestep", "inf"}), "--timestep must be a positive, finite number of seconds, got 'inf'");
  EXPECT_EQ(usage_error({"--timestep", "1e999"}),
            "--timestep must be a positive, finite number of seconds, got '1e999'");
  EXPECT_EQ(usage_error({"--timestep", "0.002s"}),
            "--timestep must be a positive, finite number of seconds, got '0.002s'");
  EXPECT_EQ(usage_error({"--steps", "0"}), "--steps must be a whole number from 1 to 4611686018427387903, got '0'");
  EXPECT_EQ(usage_error({"--steps", "-5"}), "--steps must be a whole number from 1 to 4611686018427387903, got '-5'");
  EXPECT_EQ(usage_error({"--steps", "2.5"}), "--steps must be a whole number from 1 to 4611686018427387903, got '2.5'");
  EXPECT_EQ(usage_error({"--seed", "-1"}),
            "--seed must be a whole number from 0 to 18446744073709551615, got '-1'");
  EXPECT_EQ(usage_error({"--seed", "18446744073709551616"}),
            "--seed must be a whole number from 0 to 18446744073709551615, got '18446744073709551616'");
  EXPECT_EQ(usage_error({"--seed", "abc"}), "--seed must be a whole number from 0 to 18446744073709551615, got 'abc'");
  EXPECT_EQ(usage_error({"--record-every", "0"}),
            "--record-every must be a whole number from 1 to 4611686018427387903, got '0'");
  EXPECT_EQ(usage_error({"--seed"}), "--seed needs a value");
  EXPECT_EQ(usage_error({"--out", ""}), "--out must name a directory, got ''");
  EXPECT_EQ(usage_error({"--model="}), "--model must name an MJCF file, got ''");
  EXPECT_EQ(usage_error({"--frobnicate"}), "unknown option '--frobnicate' (see --help)");
  EXPECT_EQ(usage_error({"seed"}), "unexpected argument 'seed' (see --help)");
  EXPECT_EQ(usage_error({"--smoke=yes"}), "--smoke takes no value, got 'yes'");
  EXPECT_EQ(usage_error({"--rng", "pcg64"}), "--rng must be mt19937_64 or numpy, got 'pcg64'");
  EXPECT_EQ(usage_error({"--rng"}), "--rng needs a value");
  EXPECT_EQ(usage_error({"sweep", "--rng", "numpy"}), "--rng is not a sweep option (see sweep --help)");
  const std::string huge = usage_error({"--steps", "4000000000000"});
  EXPECT_NE(huge.find("raise record_every"), std::string::npos) << huge;
}

}  // namespace
