// sim_loop stopped or failing as a user meets it: signals at any moment, a
// full disk, outputs that cannot be replaced, a full or closed stdout, a
// failing or stopped --plot, no memory. Always one line, and the earlier
// outputs kept whole.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "command_util.hpp"
#include "simloop/chapter_scene.hpp"
#include "simloop/model.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

using test::Background;
using test::names_in;
using test::Outcome;
using test::shell_quote;
using test::sim_loop;
using test::snapshot;

// Item 8: Ctrl-C (SIGINT) and SIGTERM stop a long run or sweep within 0.2 s,
// exit 130 / 143 with one line, and leave the earlier outputs as they were.
TEST(Command, SignalsStopLongWorkPromptlyAndKeepTheEarlierOutputs) {
  test::TempDir dir;
  ASSERT_EQ(sim_loop(dir.path(), {"--smoke", "--out", "out"}).exit_code, 0);
  const auto before = snapshot(dir.path() / "out");
  const std::vector<std::vector<std::string>> commands = {
      {"--steps", "100000000", "--record-every", "100", "--out", "out"},
      // Many runs of up to 200000 steps: a single run of 10^7 steps would
      // spend its first seconds allocating the sweep's in-memory trajectory,
      // where no stop is checked (left to the sweep's memory work, item 5).
      {"sweep", "--range", "0.0001:0.001:200", "--duration", "20", "--out", "out"}};
  for (const auto& args : commands) {
    for (const int sig : {SIGINT, SIGTERM}) {
      SCOPED_TRACE(args.front() + (sig == SIGINT ? " SIGINT" : " SIGTERM"));
      Background child(dir.path(), args);
      ASSERT_TRUE(child.started());
      double seconds = 0;
      const Outcome o = child.signal_after(std::chrono::milliseconds(500), sig, &seconds);
      EXPECT_EQ(o.exit_code, 128 + sig) << o.err;
      EXPECT_LT(seconds, 0.2) << "from the signal to the exit";
      EXPECT_EQ(o.err.rfind("sim_loop: interrupted (", 0), 0u) << o.err;
      EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
      EXPECT_EQ(snapshot(dir.path() / "out"), before) << "the earlier outputs changed, or a file was left";
    }
  }
}

// Item 3 and 4: a signal at any moment, the write window included, leaves
// all the old outputs or all the new ones, and no temporary file.
TEST(Command, SignalsAtRandomMomentsLeaveAllOldOrAllNewOutputs) {
  test::TempDir dir;
  const std::vector<std::string> common = {"--steps", "20000", "--out"};
  const auto run_into = [&](const char* seed, const char* out) {
    std::vector<std::string> args = {"--seed", seed};
    args.insert(args.end(), common.begin(), common.end());
    args.emplace_back(out);
    return sim_loop(dir.path(), args);
  };
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(run_into("2", "new").exit_code, 0);
  const double run_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(run_into("1", "old").exit_code, 0);
  const std::string old_metrics = test::read_text(dir.path() / "old" / "metrics.json");
  const std::string old_csv = test::read_text(dir.path() / "old" / "trajectory.csv");
  const std::string new_metrics = test::read_text(dir.path() / "new" / "metrics.json");
  const std::string new_csv = test::read_text(dir.path() / "new" / "trajectory.csv");
  ASSERT_NE(old_csv, new_csv);
  std::mt19937 random(8);  // seeded: the same moments every time
  std::uniform_real_distribution<double> moment(0.0, run_seconds * 1.2);
  int kept_old = 0, got_new = 0;
  for (int attempt = 0; attempt < 20; ++attempt) {
    const int sig = attempt % 2 ? SIGTERM : SIGINT;
    const fs::path out = dir.path() / "out";
    fs::remove_all(out);
    fs::copy(dir.path() / "old", out);
    Background child(dir.path(), {"--seed", "2", "--steps", "20000", "--out", "out"});
    ASSERT_TRUE(child.started());
    double seconds = 0;
    const Outcome o = child.signal_after(std::chrono::duration<double>(moment(random)), sig, &seconds);
    SCOPED_TRACE("attempt " + std::to_string(attempt) + ": " + o.err);
    EXPECT_TRUE(o.exit_code == 0 || o.exit_code == 128 + sig) << o.exit_code;
    ASSERT_EQ(names_in(out), (std::set<std::string>{"metrics.json", "trajectory.csv"})) << "a file was left";
    const std::string metrics = test::read_text(out / "metrics.json");
    const std::string csv = test::read_text(out / "trajectory.csv");
    const bool all_old = metrics == old_metrics && csv == old_csv;
    const bool all_new = metrics == new_metrics && csv == new_csv;
    EXPECT_TRUE(all_old || all_new) << "a mix of old and new outputs";
    kept_old += all_old;
    got_new += all_new;
  }
  std::printf("signals at random moments: %d runs kept the old outputs, %d wrote the new\n", kept_old, got_new);
}

// Item 3: a full disk (a file-size limit, then a 200 kB tmpfs where one can
// be mounted) fails with one line and leaves no temporary file, however many
// runs fail; a run that fits still succeeds after them.
TEST(Command, AFullDiskLeavesTheEarlierOutputsAndNoTemporaryFiles) {
  test::TempDir dir;
  ASSERT_EQ(sim_loop(dir.path(), {"--smoke", "--out", "out"}).exit_code, 0);  // about 100 kB
  const auto before = snapshot(dir.path() / "out");
  for (int attempt = 0; attempt < 3; ++attempt) {
    const Outcome o = sim_loop(dir.path(), {"--steps", "2000", "--out", "out"}, "ulimit -f 200 &&");
    EXPECT_EQ(o.exit_code, 1) << o.err;
    EXPECT_NE(o.err.find("out/trajectory.csv: cannot write (File too large)"), std::string::npos) << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    EXPECT_EQ(snapshot(dir.path() / "out"), before);
  }
  EXPECT_EQ(sim_loop(dir.path(), {"--smoke", "--seed", "4", "--out", "out"}, "ulimit -f 200 &&").exit_code, 0);

  const fs::path small = dir.path() / "small";
  fs::create_directories(small);
  if (::mount("tmpfs", small.c_str(), "tmpfs", 0, "size=200k") != 0) {
    GTEST_SKIP() << "cannot mount a tmpfs here (not root?): the file-size limit case ran";
  }
  for (int attempt = 0; attempt < 7; ++attempt) {
    const Outcome o = sim_loop(dir.path(), {"--steps", "2000", "--out", "small"});
    EXPECT_EQ(o.exit_code, 1) << o.err;
    EXPECT_NE(o.err.find("small/trajectory.csv: cannot write (No space left on device)"), std::string::npos) << o.err;
    EXPECT_EQ(names_in(small), std::set<std::string>{}) << "attempt " << attempt;
  }
  EXPECT_EQ(sim_loop(dir.path(), {"--smoke", "--out", "small"}).exit_code, 0) << "a run that fits";
  EXPECT_EQ(names_in(small), (std::set<std::string>{"metrics.json", "trajectory.csv"}));
  ::umount(small.c_str());
}

// Item 4: the two outputs are replaced together or not at all.
TEST(Command, BothOutputsAreReplacedOrNeither) {
  test::TempDir dir;
  for (const char* blocked : {"metrics.json", "trajectory.csv"}) {
    SCOPED_TRACE(blocked);
    ASSERT_EQ(sim_loop(dir.path(), {"--smoke", "--out", "out"}).exit_code, 0);
    fs::remove(dir.path() / "out" / blocked);
    fs::create_directories(dir.path() / "out" / blocked / "inside");
    const auto before = snapshot(dir.path() / "out");
    const Outcome o = sim_loop(dir.path(), {"--smoke", "--seed", "9", "--out", "out"});
    EXPECT_EQ(o.exit_code, 1);
    EXPECT_EQ(o.err, "sim_loop: out/" + std::string(blocked) + ": cannot replace (is a directory)\n");
    EXPECT_EQ(snapshot(dir.path() / "out"), before);
    fs::remove_all(dir.path() / "out");
  }
  ASSERT_EQ(sim_loop(dir.path(), {"--smoke", "--out", "out"}).exit_code, 0);
  const auto before = snapshot(dir.path() / "out");
  const std::string metrics = (dir.path() / "out" / "metrics.json").string();
  if (std::system(("chattr +i " + shell_quote(metrics) + " 2>/dev/null").c_str()) != 0) {
    GTEST_SKIP() << "chattr +i is not available here";
  }
  const Outcome o = sim_loop(dir.path(), {"--smoke", "--seed", "9", "--out", "out"});
  EXPECT_EQ(std::system(("chattr -i " + shell_quote(metrics)).c_str()), 0);
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_EQ(o.err, "sim_loop: out/metrics.json: cannot replace (Operation not permitted)\n");
  EXPECT_EQ(snapshot(dir.path() / "out"), before);
}

// Item 12: a report that cannot be written is a failure: exit 1, one line.
TEST(Command, AFullOrClosedStdoutExitsOne) {
  test::TempDir dir;
  for (const std::string& to : {std::string("> /dev/full"), std::string(">&-")}) {
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"--smoke"}, std::vector<std::string>{"--help"},
          std::vector<std::string>{"--version"}, std::vector<std::string>{"sweep", "--timesteps", "0.002"}}) {
      SCOPED_TRACE(to + " " + args.front());
      const Outcome o = sim_loop(dir.path(), args, "", to);
      EXPECT_EQ(o.exit_code, 1);
      EXPECT_EQ(o.err.rfind("sim_loop: ", 0), 0u) << o.err;
      EXPECT_NE(o.err.find("standard output"), std::string::npos) << o.err;
      EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    }
  }
  EXPECT_FALSE(fs::exists(dir.path() / "outputs")) << "nothing is run when the report cannot be written";
}

// Item 12: --plot failing says so in one line, after the outputs were written.
TEST(Command, APlotFailureIsOneLine) {
  test::TempDir dir;
  const fs::path fake = dir.path() / "fake-python";
  test::write_text(fake,
                   "#!/bin/sh\n"
                   "echo 'Traceback (most recent call last):' >&2\n"
                   "echo '  File \"<frozen runpy>\", line 198, in _run_module_as_main' >&2\n"
                   "echo \"ModuleNotFoundError: No module named 'matplotlib'\" >&2\n"
                   "exit 1\n");
  fs::permissions(fake, fs::perms::owner_all);
  const Outcome o =
      sim_loop(dir.path(), {"--smoke", "--plot", "--out", "out"}, "SIMLOOP_PYTHON=" + shell_quote(fake.string()));
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
  EXPECT_EQ(o.err.rfind("sim_loop: --plot: ", 0), 0u) << o.err;
  EXPECT_NE(o.err.find("No module named 'matplotlib'"), std::string::npos) << o.err;
  EXPECT_NE(o.out.find("metrics: out/metrics.json\n"), std::string::npos) << o.out;
  EXPECT_TRUE(fs::is_regular_file(dir.path() / "out" / "metrics.json"));
}

// Item 8: a stop while the chart is drawn ends the plotting process (and what
// it started) at once; the outputs, written before, are complete.
TEST(Command, ASignalWhilePlottingStopsPromptly) {
  test::TempDir dir;
  const fs::path slow = dir.path() / "slow-python";
  test::write_text(slow, "#!/bin/sh\nsleep 30\n");  // a plotter that hangs, through a grandchild
  fs::permissions(slow, fs::perms::owner_all);
  ::setenv("SIMLOOP_PYTHON", slow.c_str(), 1);
  Background child(dir.path(), {"--smoke", "--plot", "--out", "out"});
  ::unsetenv("SIMLOOP_PYTHON");
  ASSERT_TRUE(child.started());
  double seconds = 0;
  const Outcome o = child.signal_after(std::chrono::milliseconds(500), SIGINT, &seconds);
  EXPECT_EQ(o.exit_code, 130) << o.err;
  EXPECT_LT(seconds, 0.2);
  EXPECT_EQ(o.err, "sim_loop: interrupted (SIGINT); after the outputs were written\n");
  EXPECT_EQ(names_in(dir.path() / "out"), (std::set<std::string>{"metrics.json", "trajectory.csv"}));
}

// Item 13: running out of memory names what was being done, with which inputs.
TEST(Command, OutOfMemorySaysWhatWasBeingDone) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer cannot start under ulimit -v";
#endif
  // A sweep no longer keeps trajectories (it reduces them as it goes), so
  // what runs out of memory now is a scene that asks for a 480 MB stack.
  test::TempDir dir;
  std::string xml(simloop::pusher_scene_xml());
  xml.insert(xml.find('>') + 1, "<size nstack=\"60000000\"/>");
  test::write_text(dir.path() / "big.xml", xml);
  for (const std::vector<std::string>& args : {std::vector<std::string>{"--model", "big.xml", "--out", "s"},
                                               std::vector<std::string>{"sweep", "--model", "big.xml", "--out", "s"}}) {
    const Outcome o = sim_loop(dir.path(), args, "ulimit -v 300000 &&");
    EXPECT_EQ(o.exit_code, 2);
    EXPECT_EQ(o.err, "sim_loop: --model: big.xml: Error: engine error: Could not allocate memory\n");
    EXPECT_FALSE(fs::exists(dir.path() / "s" / "sweep.csv"));
    EXPECT_FALSE(fs::exists(dir.path() / "s" / "metrics.json"));
  }
}

}  // namespace
