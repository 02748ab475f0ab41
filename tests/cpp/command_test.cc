// sim_loop as a user runs it: a real process in a scratch directory. Its
// help and version, the chapter's run and Break It, the sweep, bad input;
// stops and failures are in command_failures_test.cc.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "command_util.hpp"
#include "expected.hpp"
#include "simloop/model.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

using test::lines_of;
using test::Outcome;
using test::read_csv;
using test::sim_loop;
using test::snapshot;

TEST(Command, Help) {
  test::TempDir dir;
  const Outcome o = sim_loop(dir.path(), {"--help"});
  EXPECT_EQ(o.exit_code, 0);
  EXPECT_EQ(o.out.rfind("usage: sim_loop", 0), 0u);
  for (const char* flag : {"--seed", "--steps", "--timestep", "--smoke", "--out", "--no-perturb", "--rerun",
                           "--no-rerun", "--record-every", "--model", "--version", "--help"}) {
    EXPECT_NE(o.out.find(flag), std::string::npos) << flag;
  }
  EXPECT_TRUE(o.err.empty());
  EXPECT_FALSE(fs::exists(dir.path() / "outputs"));
}

// plot is parsed by the commands' one parser, and drawn by the Python package.
TEST(Command, PlotIsThePythonPackagesCommand) {
  test::TempDir dir;
  const Outcome o = sim_loop(dir.path(), {"plot", "trajectory", "--x", "step"});
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_EQ(o.err,
            "sim_loop: plot is a command of the Python package: python -m simloop plot (see python -m simloop plot "
            "--help)\n");
  EXPECT_TRUE(o.out.empty());
  EXPECT_FALSE(fs::exists(dir.path() / "outputs"));
}

// So is batch (pyarrow, Dask).
TEST(Command, BatchIsThePythonPackagesCommand) {
  test::TempDir dir;
  const Outcome o = sim_loop(dir.path(), {"batch", "--seeds", "0:4"});
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_EQ(o.err,
            "sim_loop: batch is a command of the Python package: python -m simloop batch (see python -m simloop "
            "batch --help)\n");
  EXPECT_TRUE(o.out.empty());
  EXPECT_FALSE(fs::exists(dir.path() / "outputs"));
}

TEST(Command, VersionIsTheProjectVersion) {
  test::TempDir dir;
  const Outcome o = sim_loop(dir.path(), {"--version"});
  EXPECT_EQ(o.exit_code, 0);
  EXPECT_EQ(o.out, std::string("sim_loop ") + SIMLOOP_VERSION_STRING + " (MuJoCo " + mj_versionString() + ")\n");
}

TEST(Command, DefaultRunReportsAndWritesTheChaptersFiles) {
  test::TempDir dir;
  const Outcome o = sim_loop(dir.path(), {"--seed", "0"});
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_TRUE(o.err.empty()) << o.err;
  const auto lines = lines_of(o.out);
  ASSERT_GE(lines.size(), 7u);
  EXPECT_EQ(lines[0], std::string("ch0.1-sim-loop | tier: cpu | MuJoCo ") + mj_versionString() +
                          " | simloop " SIMLOOP_VERSION_STRING);
  EXPECT_EQ(lines[1], "stepped 2000 steps of 0.002 s -> 4.00 s of sim time");
  EXPECT_EQ(lines[2].rfind("box final position [", 0), 0u);
  EXPECT_EQ(lines[3].rfind("shove: +7.0 N in y for 50 steps -> ", 0), 0u);
  EXPECT_EQ(lines[4], "metrics: outputs/ch0.1-sim-loop/metrics.json");
  EXPECT_EQ(lines[5], "trajectory: outputs/ch0.1-sim-loop/trajectory.csv (2001 rows)");
  EXPECT_EQ(lines.back().rfind("wall-clock: ", 0), 0u);
  const fs::path out = dir.path() / "outputs" / "ch0.1-sim-loop";
  const std::string metrics = test::read_text(out / "metrics.json");
  EXPECT_NE(metrics.find("\"seed\": 0,"), std::string::npos);
  EXPECT_NE(metrics.find("\"steps\": 2000\n"), std::string::npos);
  EXPECT_EQ(read_csv(out / "trajectory.csv").at("step").size(), 2001u);
  EXPECT_FALSE(fs::exists(dir.path() / "MUJOCO_LOG.TXT"));
}

TEST(Command, TwoRunsAreByteIdentical) {
  test::TempDir dir;
  for (const std::vector<std::string>& flags :
       {std::vector<std::string>{"--smoke"}, std::vector<std::string>{"--seed", "3", "--record-every", "4"}}) {
    std::vector<std::string> a = flags, b = flags;
    a.insert(a.end(), {"--out", "a"});
    b.insert(b.end(), {"--out", "b"});
    const Outcome first = sim_loop(dir.path(), a);
    const Outcome second = sim_loop(dir.path(), b);
    ASSERT_EQ(first.exit_code, 0) << first.err;
    ASSERT_EQ(second.exit_code, 0) << second.err;
    for (const char* file : {"metrics.json", "trajectory.csv"}) {
      const std::string bytes = test::read_text(dir.path() / "a" / file);
      EXPECT_FALSE(bytes.empty());
      EXPECT_EQ(bytes, test::read_text(dir.path() / "b" / file)) << file;
    }
    fs::remove_all(dir.path() / "a");
    fs::remove_all(dir.path() / "b");
  }
}

// Break It, through the command as the chapter runs it:
// `sim_loop --timestep 0.05 --no-perturb` against the default timestep.
TEST(Command, BreakItTheCoarseTimestepHopsAndDrifts) {
  test::TempDir dir;
  ASSERT_EQ(sim_loop(dir.path(), {"--timestep", "0.05", "--no-perturb", "--out", "coarse"}).exit_code, 0);
  ASSERT_EQ(sim_loop(dir.path(), {"--no-perturb", "--out", "fine"}).exit_code, 0);
  const auto coarse = read_csv(dir.path() / "coarse" / "trajectory.csv");
  const auto fine = read_csv(dir.path() / "fine" / "trajectory.csv");
  const auto max_of = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
  const auto max_abs = [](const std::vector<double>& v) {
    double m = 0;
    for (double x : v) m = std::max(m, std::fabs(x));
    return m;
  };
  // Measured: peak z 0.0927 m vs 0.0535 m; final y -0.254 m vs largest |y| 0.0515 m.
  EXPECT_GT(max_of(coarse.at("box_z")), 0.085);
  EXPECT_LT(max_of(fine.at("box_z")), 0.056);
  SIMLOOP_EXPECTED(double, final_y_min, "break_it.final_y_min");
  SIMLOOP_EXPECTED(double, final_y_max, "break_it.final_y_max");
  EXPECT_GE(coarse.at("box_y").back(), final_y_min);
  EXPECT_LE(coarse.at("box_y").back(), final_y_max);
  EXPECT_LT(max_abs(fine.at("box_y")), 0.07);
  // And nothing pushed sideways: every shove cell is zero (or empty, last row).
  for (double f : coarse.at("shove_y")) EXPECT_TRUE(f == 0.0 || std::isnan(f));
}

TEST(Command, SweepNamesTheEdgeAndWritesItsCsv) {
  test::TempDir dir;
  const Outcome o = sim_loop(dir.path(), {"sweep", "--timesteps", "0.002,0.004,0.005,0.5", "--out", "s"});
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("largest stable timestep: 0.004 s\n"), std::string::npos) << o.out;
  const auto csv = read_csv(dir.path() / "s" / "sweep.csv");
  EXPECT_EQ(csv.at("timestep"), (std::vector<double>{0.002, 0.004, 0.005, 0.5}));
  EXPECT_EQ(csv.at("stable"), (std::vector<double>{1, 1, 0, 0}));
  EXPECT_EQ(csv.at("steps"), (std::vector<double>{2000, 1000, 800, 8}));
  const Outcome help = sim_loop(dir.path(), {"sweep", "--help"});
  EXPECT_EQ(help.out.rfind("usage: sim_loop sweep", 0), 0u);
}

struct BadInput {
  std::vector<std::string> args;
  int exit_code;
  std::string message_part;  // stderr must contain this
};

TEST(Command, BadInputGetsOneLineAndChangesNothing) {
  test::TempDir dir;
  ASSERT_EQ(sim_loop(dir.path(), {"--smoke", "--out", "out"}).exit_code, 0);
  test::write_text(dir.path() / "not_a_dir", "precious");
  test::write_text(dir.path() / "broken.xml", "<mujoco><worldbody><body></mujoco>");
  test::write_text(dir.path() / "no_box.xml",
                   "<mujoco><worldbody><body name=\"crate\"><freejoint/><geom size=\"0.1\"/></body>"
                   "</worldbody></mujoco>");
  const auto before = snapshot(dir.path());

  const std::vector<BadInput> cases = {
      {{"--timestep", "0"}, 2, "--timestep must be a positive, finite number of seconds, got '0'"},
      {{"--timestep", "-0.002"}, 2, "--timestep must be a positive, finite number of seconds, got '-0.002'"},
      {{"--timestep", "nan"}, 2, "--timestep must be a positive, finite number of seconds, got 'nan'"},
      {{"--timestep", "inf"}, 2, "--timestep must be a positive, finite number of seconds, got 'inf'"},
      {{"--steps", "0"}, 2, "--steps must be a whole number from 1 to"},
      {{"--steps", "-10"}, 2, "got '-10'"},
      {{"--steps", "1.5"}, 2, "got '1.5'"},
      {{"--seed", "-1"}, 2, "--seed must be a whole number from 0 to 18446744073709551615, got '-1'"},
      {{"--seed", "one"}, 2, "got 'one'"},
      {{"--record-every", "0"}, 2, "--record-every must be a whole number from 1 to"},
      {{"--out", "not_a_dir"}, 2, "--out: not_a_dir: exists and is not a directory"},
      {{"--out", "not_a_dir/sub"}, 2, "--out: not_a_dir/sub: cannot create the output directory"},
      {{"--out", "/proc/self/simloop"}, 2, "--out: /proc/self/simloop: cannot create the output directory"},
      {{"--model", "missing.xml"}, 2, "--model: missing.xml: cannot open (No such file or directory)"},
      {{"--model", "broken.xml"}, 2, "--model: broken.xml: XML parse error"},
      {{"--model", "no_box.xml"}, 2, "--model: no_box.xml: the model has no body named \"box\""},
      {{"--bogus"}, 2, "unknown option '--bogus'"},
      {{"sweep", "--duration", "0"}, 2, "--duration must be a positive, finite number of seconds, got '0'"},
      {{"sweep", "--threads", "0"}, 2, "--threads must be a whole number from 1 to 4096, got '0'"},
      {{"sweep", "--timesteps", "0.001,x"}, 2, "--timesteps must be a positive, finite number of seconds, got 'x'"},
      {{"sweep", "--range", "0.1:0.001:5"},
       2,
       "--range: timestep range must run from a positive timestep up to a larger one"},
      {{"sweep", "--range", "0.001:0.1"}, 2, "--range must be FROM:TO:COUNT, got '0.001:0.1'"},
      {{"sweep", "--seed", "1"}, 2, "--seed is not a sweep option"},
      {{"--threads", "2"}, 2, "--threads belongs to the sweep command"},
  };
  for (const BadInput& c : cases) {
    std::vector<std::string> args = c.args;
    if (std::find(args.begin(), args.end(), "--out") == args.end()) args.insert(args.end(), {"--out", "out"});
    const Outcome o = sim_loop(dir.path(), args);
    SCOPED_TRACE(c.args.front() + " " + (c.args.size() > 1 ? c.args[1] : "") + " " +
                 (c.args.size() > 2 ? c.args[2] : ""));
    EXPECT_EQ(o.exit_code, c.exit_code);
    EXPECT_EQ(o.err.rfind("sim_loop: ", 0), 0u) << o.err;
    EXPECT_NE(o.err.find(c.message_part), std::string::npos) << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << "one line: " << o.err;
    EXPECT_EQ(snapshot(dir.path()), before) << "outputs changed";
  }
  EXPECT_FALSE(fs::exists(dir.path() / "MUJOCO_LOG.TXT"));
}

}  // namespace
