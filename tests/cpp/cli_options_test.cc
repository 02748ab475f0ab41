#include "cli_options.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include "simloop/errors.hpp"

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

TEST(CliOptions, ChapterDrawsTheShoveAsTheChapterDoes) {
  // The book's seed 0 shove is +9.8 N: numpy's default_rng, not the default generator.
  const simloop::cli::Options o = parse({"--chapter"});
  EXPECT_EQ(o.run.rng, simloop::ShoveRng::kNumpy);
  EXPECT_NEAR(simloop::draw_shove(o.run.seed, o.run.num_steps(), o.run.rng).force_y(), 9.8, 0.05);
  EXPECT_EQ(parse({"--rng", "numpy", "--chapter"}).run.rng, simloop::ShoveRng::kNumpy);
  EXPECT_EQ(usage_error({"--chapter", "--rng", "mt19937_64"}),
            "--chapter draws the shove as the chapter does (--rng numpy); it cannot be combined with --rng mt19937_64");
  EXPECT_EQ(usage_error({"--chapter=yes"}), "--chapter takes no value, got 'yes'");
  EXPECT_EQ(usage_error({"sweep", "--chapter"}), "--chapter is not a sweep option (see sweep --help)");
}

TEST(CliOptions, VideoNamesAFileForARun) {
  EXPECT_TRUE(parse({}).video.empty());
  EXPECT_EQ(parse({"--video", "run.mp4"}).video, "run.mp4");
  EXPECT_EQ(parse({"--video=clips/run.png", "--no-rerun"}).video, "clips/run.png");
  EXPECT_EQ(usage_error({"--video="}), "--video must name a file (.mp4 or .png), got ''");
  EXPECT_EQ(usage_error({"sweep", "--video", "x.mp4"}), "--video is not a sweep option (see sweep --help)");
}

TEST(CliOptions, ParsesEveryFlagInBothSpellings) {
  const auto o = parse({"--seed", "18446744073709551615", "--steps=10", "--timestep", "0.05", "--smoke", "--out=o",
                        "--no-perturb", "--no-rerun", "--record-every", "5", "--model", "m.xml"});
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
            "--timestep must be a positive, finite number of seconds without a unit (0.002, not 0.002s), got '0.002s'");
  EXPECT_EQ(usage_error({"--timestep", "2ms"}),
            "--timestep must be a positive, finite number of seconds without a unit (0.002, not 0.002s), got '2ms'");
  EXPECT_EQ(usage_error({"--timestep", "1e"}), "--timestep must be a positive, finite number of seconds, got '1e'");
  EXPECT_EQ(usage_error({"--steps", "0"}), "--steps must be a whole number from 1 to 4611686018427387903, got '0'");
  EXPECT_EQ(usage_error({"--steps", "-5"}), "--steps must be a whole number from 1 to 4611686018427387903, got '-5'");
  EXPECT_EQ(usage_error({"--steps", "2.5"}), "--steps must be a whole number from 1 to 4611686018427387903, got '2.5'");
  EXPECT_EQ(usage_error({"--seed", "-1"}), "--seed must be a whole number from 0 to 18446744073709551615, got '-1'");
  EXPECT_EQ(usage_error({"--seed", "18446744073709551616"}),
            "--seed must be a whole number from 0 to 18446744073709551615, got '18446744073709551616'");
  EXPECT_EQ(usage_error({"--seed", "abc"}), "--seed must be a whole number from 0 to 18446744073709551615, got 'abc'");
  EXPECT_EQ(usage_error({"--record-every", "0"}),
            "--record-every must be a whole number from 1 to 4611686018427387903, got '0'");
  EXPECT_EQ(usage_error({"--seed"}), "--seed needs a value");
  // A forgotten value does not swallow the next flag; --out=--x is a folder named so.
  EXPECT_EQ(
      usage_error({"--out", "--no-perturb"}),
      "--out needs a value, got the flag --no-perturb (write --out=--no-perturb for a value that begins with --)");
  EXPECT_EQ(usage_error({"--out", "--seed", "3"}),
            "--out needs a value, got the flag --seed (write --out=--seed for a value that begins with --)");
  EXPECT_EQ(parse({"--out=--x"}).out, std::filesystem::path("--x"));
  EXPECT_EQ(usage_error({"--seed", "-1"}).rfind("--seed must be a whole number", 0), 0u);
  EXPECT_EQ(usage_error({"--out", ""}), "--out must name a directory, got ''");
  EXPECT_EQ(usage_error({"--model="}), "--model must name an MJCF file, got ''");
  EXPECT_EQ(usage_error({"--frobnicate"}), "unknown option '--frobnicate' (see --help)");
  EXPECT_EQ(usage_error({"seed"}), "unexpected argument 'seed' (see --help)");
  EXPECT_EQ(usage_error({"--seed", "1", "batch"}), "unexpected argument 'batch' (see --help)");
  EXPECT_EQ(usage_error({"--smoke=yes"}), "--smoke takes no value, got 'yes'");
  EXPECT_EQ(usage_error({"--rng", "pcg64"}), "--rng must be mt19937_64 or numpy, got 'pcg64'");
  EXPECT_EQ(usage_error({"--rng"}), "--rng needs a value");
  EXPECT_EQ(usage_error({"sweep", "--rng", "numpy"}), "--rng is not a sweep option (see sweep --help)");
}

TEST(CliOptions, NumbersAreWrittenPlainlyForEveryFlag) {
  // --steps refused " 5" while --timestep took " 5", "+5", hex and hex floats.
  for (const char* bad : {" 5", "5 ", "+5", "0x10", "0x1p-3", "1e", ".", "-", "5e+", "1,5", "infinity", "1_0"}) {
    SCOPED_TRACE(bad);
    EXPECT_NE(usage_error({"--timestep", bad}).find("--timestep must be a positive, finite number of seconds"),
              std::string::npos);
    EXPECT_NE(usage_error({"--steps", bad}).find("--steps must be a whole number"), std::string::npos);
  }
  EXPECT_EQ(parse({"--timestep", "5"}).run.timestep, 5.0);
  EXPECT_EQ(parse({"--timestep", "5."}).run.timestep, 5.0);
  EXPECT_EQ(parse({"--timestep", ".5"}).run.timestep, 0.5);
  EXPECT_EQ(parse({"--timestep", "2e-3"}).run.timestep, 0.002);
  EXPECT_EQ(parse({"--timestep", "2E+0"}).run.timestep, 2.0);
  EXPECT_EQ(usage_error({"sweep", "--timesteps", "0.001, 0.002"}),
            "--timesteps must be a positive, finite number of seconds, got ' 0.002'");
}

TEST(CliOptions, FlagsWithoutValuesRefuseOne) {
  EXPECT_EQ(usage_error({"--help=x"}), "--help takes no value, got 'x'");
  EXPECT_EQ(usage_error({"--version=x"}), "--version takes no value, got 'x'");
  EXPECT_EQ(usage_error({"--help="}), "--help takes no value, got ''");
}

TEST(CliOptions, EchoedValuesAreEscapedOntoOneLine) {
  EXPECT_EQ(usage_error({"--steps", "x'y"}),
            "--steps must be a whole number from 1 to 4611686018427387903, got 'x\\'y'");
  EXPECT_EQ(usage_error({"--timestep", "a\nb\\c"}),
            "--timestep must be a positive, finite number of seconds, got 'a\\x0ab\\\\c'");
  EXPECT_EQ(usage_error({"--bogus\r"}), "unknown option '--bogus\\x0d' (see --help)");
}

TEST(CliOptions, SweepPointsMustBeRunnableAsAsked) {
  // These ran one step and exited 0, or failed midway, before.
  EXPECT_EQ(usage_error({"sweep", "--duration", "1e300", "--timesteps", "0.01"}),
            "--timesteps/--duration: duration 1e+300 s at timestep 0.01 s is 1e+302 steps; a sweep point needs 4 to "
            "4611686018427387903 steps (duration / timestep, rounded)");
  EXPECT_EQ(usage_error({"sweep", "--timesteps", "1e-300,0.002"})
                .rfind("--timesteps/--duration: duration 4.0 s at "
                       "timestep 1e-300 s is 4e+300 steps",
                       0),
            0u);
  EXPECT_EQ(usage_error({"sweep", "--duration", "9e18"}).rfind("--duration: duration 9e+18 s at timestep 0.0005 s", 0),
            0u);
  EXPECT_EQ(usage_error({"sweep", "--range", "0.5:2:3", "--duration", "4"})
                .rfind("--range/--duration: duration 4.0 s "
                       "at timestep 2.0 s is 2 steps",
                       0),
            0u);
  EXPECT_NO_THROW((void)parse({"sweep"}));
  EXPECT_TRUE(parse({"sweep", "--duration", "1e300", "--help"}).help);
}

TEST(CliOptions, StepsAndRecordEveryShareTheLibrarysRange) {
  EXPECT_EQ(parse({"--steps", "4611686018427387903", "--record-every", "4611686018427387903"}).run.steps,
            simloop::kMaxSteps);
  EXPECT_EQ(usage_error({"--steps", "4611686018427387904"}),
            "--steps must be a whole number from 1 to 4611686018427387903, got '4611686018427387904'");
  EXPECT_EQ(usage_error({"--record-every", "4611686018427387904"}),
            "--record-every must be a whole number from 1 to 4611686018427387903, got '4611686018427387904'");
}

TEST(CliOptions, AHugeRunIsTheLibrarysToRefuseOnlyIfItKeepsItsRows) {
  // The parser takes any steps in range: sim_loop may stream the rows to a
  // file. Keeping them in memory is what the library refuses, up front.
  const auto o = parse({"--steps", "4000000000000"});
  EXPECT_EQ(o.run.steps, 4000000000000);
  try {
    simloop::check_kept_rows({simloop::kept_rows(o.run)});
    ADD_FAILURE() << "accepted";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("raise record_every"), std::string::npos) << e.what();
  }
}

// `batch` (python -m simloop's): parse_batch, command/cli_batch.cc.
std::vector<std::uint64_t> seeds(const simloop::cli::BatchOptions& b) {
  std::vector<std::uint64_t> out;
  for (const auto& r : b.seeds) {
    for (std::uint64_t s = r.first;; s += r.step) {
      out.push_back(s);
      if (r.last - s < r.step) break;  // (s + step may pass 2^64-1)
    }
  }
  return out;
}

TEST(CliBatch, DefaultsAreOneRunOfTheScenario) {
  const auto o = parse({"batch"});
  EXPECT_EQ(o.command, simloop::cli::Command::kBatch);
  EXPECT_EQ(seeds(o.batch), std::vector<std::uint64_t>{0});
  EXPECT_TRUE(o.batch.timesteps.empty());
  EXPECT_TRUE(o.batch.params.empty());
  EXPECT_EQ(o.batch.steps, 0);
  EXPECT_EQ(o.batch.rng, "mt19937_64");
  EXPECT_TRUE(o.batch.perturb);
  EXPECT_EQ(o.batch.out, "outputs/batch.parquet");
  EXPECT_FALSE(o.batch.resume);
  EXPECT_FALSE(o.help);
}

TEST(CliBatch, TakesEveryFlagWithOrWithoutEquals) {
  const auto o = parse({"batch",
                        "--scenario",
                        "s.toml",
                        "--seeds=0:6,40,10:20:5",
                        "--timestep",
                        "0.002,1e-3",
                        "--friction",
                        "0.5,1",
                        "--friction=box_geom=2",
                        "--mass",
                        "box=3",
                        "--damping",
                        "j=0",
                        "--gravity",
                        "9.81",
                        "--steps",
                        "300",
                        "--rng",
                        "numpy",
                        "--no-perturb",
                        "--scheduler",
                        "tcp://h:8786",
                        "--threads",
                        "2",
                        "--chunk-size=7",
                        "--out",
                        "b.parquet",
                        "--resume",
                        "-h"});
  const simloop::cli::BatchOptions& b = o.batch;
  EXPECT_EQ(b.scenario, "s.toml");
  EXPECT_EQ(seeds(b), (std::vector<std::uint64_t>{0, 1, 2, 3, 4, 5, 40, 10, 15}));
  EXPECT_EQ(b.timesteps, (std::vector<double>{0.002, 0.001}));
  ASSERT_EQ(b.params.size(), 5u);
  EXPECT_EQ(b.params[0].kind, "friction");
  EXPECT_EQ(b.params[0].name, "");
  EXPECT_EQ(b.params[0].values, (std::vector<double>{0.5, 1.0}));
  EXPECT_EQ(b.params[1].name, "box_geom");
  EXPECT_EQ(b.params[2].kind, "mass");
  EXPECT_EQ(b.params[2].name, "box");
  EXPECT_EQ(b.params[4].kind, "gravity");
  EXPECT_EQ(b.steps, 300);
  EXPECT_EQ(b.rng, "numpy");  // the library's to check, once the scenario is loaded
  EXPECT_FALSE(b.perturb);
  EXPECT_EQ(b.scheduler, "tcp://h:8786");
  EXPECT_EQ(b.threads, 2);
  EXPECT_EQ(b.chunk_size, 7);
  EXPECT_EQ(b.out, "b.parquet");
  EXPECT_TRUE(b.resume);
  EXPECT_TRUE(o.help);
}

TEST(CliBatch, SeedsRunToTheLastOne) {
  const auto b = parse({"batch", "--seeds", "18446744073709551614:18446744073709551616"}).batch;
  EXPECT_EQ(seeds(b).size(), 2u);
  EXPECT_EQ(b.seeds[0].last, std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(parse({"batch", "--seeds", "5:6:99999999999999999999999"}).batch.seeds[0].count(), 1u);
  EXPECT_EQ(usage_error({"batch", "--seeds", "18446744073709551616"}),
            "batch: --seeds: '18446744073709551616': seeds go from 0 to 2^64-1");
  EXPECT_EQ(usage_error({"batch", "--seeds", "0:18446744073709551617"}),
            "batch: --seeds: '0:18446744073709551617': seeds go from 0 to 2^64-1");
}

TEST(CliBatch, RefusesSeedsInOneLineNamingThem) {
  for (const char* bad : {"", "1,", "a", "\xc2\xb2", "1:2:3:4", "0::2", "-1", "+1", " 1"}) {
    EXPECT_EQ(
        usage_error({"batch", "--seeds", bad}),
        "batch: --seeds: '" + std::string(bad) + "' is not seeds (N, A:B for A to B-1, A:B:STEP, joined by commas)");
  }
  EXPECT_EQ(usage_error({"batch", "--seeds", "0:4,9:3"}),
            "batch: --seeds: '9:3' is an empty range (A:B runs A to B-1)");
  EXPECT_EQ(usage_error({"batch", "--seeds", "0:4:0"}),
            "batch: --seeds: '0:4:0' is an empty range (A:B runs A to B-1)");
  // Counted before any is listed, over every range.
  EXPECT_EQ(usage_error({"batch", "--seeds", "0:10000000000"}),
            "batch: --seeds: '0:10000000000' is 10000000000 seeds; a batch runs at most 10000000 (split it)");
  EXPECT_EQ(usage_error({"batch", "--seeds", "0:18446744073709551616,0:18446744073709551616"}),
            "batch: --seeds: '0:18446744073709551616,0:18446744073709551616' is 36893488147419103232 seeds; a batch "
            "runs at most 10000000 (split it)");
  EXPECT_EQ(parse({"batch", "--seeds", "0:10000000"}).batch.seeds[0].count(), simloop::cli::kMaxBatchRuns);
}

TEST(CliBatch, RefusesNumbersThatAreNotFinite) {
  EXPECT_EQ(usage_error({"batch", "--timestep", "0.002,x"}),
            "batch: --timestep: 'x' is not a number (values are joined by commas)");
  EXPECT_EQ(usage_error({"batch", "--friction", "1,"}),
            "batch: --friction: '' is not a number (values are joined by commas)");
  EXPECT_EQ(usage_error({"batch", "--gravity", "0x10"}),
            "batch: --gravity: '0x10' is not a number (values are joined by commas)");
  for (const char* bad : {"inf", "-Infinity", "nan", "1e999"}) {
    EXPECT_EQ(usage_error({"batch", "--damping", bad}),
              "batch: --damping: '" + std::string(bad) + "' is not a finite number");
  }
  // A value's range is the library's: a negative timestep or friction parses.
  EXPECT_EQ(parse({"batch", "--timestep", "-1", "--friction", "-1"}).batch.timesteps, std::vector<double>{-1.0});
}

TEST(CliBatch, RefusesParametersWithoutTheirName) {
  EXPECT_EQ(usage_error({"batch", "--mass", "3"}), "batch: --mass: '3' needs a body: --mass BODY=KG,KG,...");
  EXPECT_EQ(usage_error({"batch", "--gravity", "g=9"}),
            "batch: --gravity: 'g=9': gravity is the whole scene's, give values only: --gravity G,G,...");
  EXPECT_EQ(usage_error({"batch", "--friction", "=1"}), "batch: --friction: '=1' has an empty name before '='");
  EXPECT_EQ(usage_error({"batch", "--friction", "1", "--friction", "2"}),
            "batch: --friction: '2': friction of everything is given twice");
  EXPECT_EQ(usage_error({"batch", "--mass", "box=1", "--mass=box=2"}),
            "batch: --mass: 'box=2': mass of 'box' is given twice");
  // The last '=' ends the name.
  const auto b = parse({"batch", "--damping", "a=b=1", "--damping", "1"}).batch;
  EXPECT_EQ(b.params[0].name, "a=b");
  EXPECT_EQ(b.params[1].name, "");
}

TEST(CliBatch, RefusesCountsOutsideTheirRange) {
  EXPECT_EQ(usage_error({"batch", "--threads", "0"}), "batch: --threads: '0' is not a whole number from 1 to 4096");
  EXPECT_EQ(usage_error({"batch", "--threads", "4611686018427387903"}),
            "batch: --threads: '4611686018427387903' is not a whole number from 1 to 4096");
  EXPECT_EQ(usage_error({"batch", "--chunk-size", "2147483648"}),
            "batch: --chunk-size: '2147483648' is not a whole number from 1 to 2147483647");
  EXPECT_EQ(usage_error({"batch", "--steps", "\xc2\xb2"}),
            "batch: --steps: '\xc2\xb2' is not a whole number from 1 to " + std::to_string(simloop::kMaxSteps));
  EXPECT_EQ(parse({"batch", "--steps", "4611686018427387903"}).batch.steps, simloop::kMaxSteps);
}

TEST(CliBatch, RefusesWhatIsNotAFlagOrLacksItsValue) {
  EXPECT_EQ(usage_error({"batch", "--bogus"}), "batch: unknown argument '--bogus' (see batch --help)");
  EXPECT_EQ(usage_error({"batch", "seeds"}), "batch: unknown argument 'seeds' (see batch --help)");
  EXPECT_EQ(usage_error({"batch", "--seed", "1"}), "batch: unknown argument '--seed' (see batch --help)");
  EXPECT_EQ(usage_error({"batch", "--out"}), "batch: --out needs a value");
  EXPECT_EQ(usage_error({"batch", "--out="}), "batch: --out: '' names no file");
  EXPECT_EQ(usage_error({"batch", "--scenario", ""}), "batch: --scenario: '' names no file");
  EXPECT_EQ(usage_error({"batch", "--resume=yes"}), "batch: --resume takes no value, got '--resume=yes'");
  EXPECT_EQ(usage_error({"batch", "--seeds", "\x1b[2J"}),
            "batch: --seeds: '\\x1b[2J' is not seeds (N, A:B for A to B-1, A:B:STEP, joined by commas)");
  // A value may begin with --, as the flag's next argument.
  EXPECT_EQ(parse({"batch", "--out", "--resume"}).batch.out, "--resume");
}

}  // namespace

// plot's flags (python -m simloop plot) are parsed here too, as every other command's.
TEST(CliOptions, PlotIsParsedByTheSameParser) {
  const auto o = parse({"plot", "trajectory", "--out", "a", "--compare=b", "--compare", "c", "--x", "step"});
  EXPECT_EQ(o.command, simloop::cli::Command::kPlot);
  EXPECT_EQ(o.plot_what, "trajectory");
  EXPECT_EQ(o.out, std::filesystem::path("a"));
  EXPECT_EQ(o.plot_compare, (std::vector<std::filesystem::path>{"b", "c"}));
  EXPECT_EQ(o.plot_x, "step");
  EXPECT_EQ(parse({"plot", "sweep"}).out, std::filesystem::path("outputs/ch0.1-sim-loop"));
  EXPECT_EQ(parse({"plot", "sweep"}).plot_x, "auto");
  EXPECT_TRUE(parse({"plot", "--help"}).help);
  EXPECT_EQ(usage_error({"plot"}), "plot needs 'trajectory' or 'sweep' first (see plot --help)");
  EXPECT_EQ(usage_error({"plot", "trajectory", "--seed", "1"}), "plot: unknown argument '--seed' (see plot --help)");
  EXPECT_EQ(usage_error({"plot", "trajectory", "--out"}), "plot: --out needs a value");
  EXPECT_EQ(usage_error({"plot", "trajectory", "--x", "sideways"}),
            "plot: --x must be auto, time or step, got 'sideways'");
  EXPECT_EQ(usage_error({"plot", "sweep", "--compare", "x"}), "plot: --compare draws trajectories only");
}
