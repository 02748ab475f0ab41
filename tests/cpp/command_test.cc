// sim_loop as a user runs it: a real process in a scratch directory.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <random>
#include <set>
#include <thread>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "expected.hpp"
#include "simloop/model.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

extern char** environ;

namespace {

struct Outcome {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs sim_loop with `args` in `cwd`, with stdin closed and a time limit so a
// hang (MuJoCo waiting for Enter, say) fails the test instead of blocking it.
// `shell_prefix` runs first in the same shell (a ulimit, say); `stdout_to`
// replaces the redirection of stdout (then o.out stays empty).
Outcome sim_loop(const fs::path& cwd, const std::vector<std::string>& args, const std::string& shell_prefix = "",
                 const std::string& stdout_to = "") {
  const fs::path out = cwd / ".stdout", err = cwd / ".stderr";
  std::string cmd = "cd " + shell_quote(cwd.string()) + " && " + shell_prefix + " timeout 60 " +
                    shell_quote(SIM_LOOP_EXE);
  for (const auto& a : args) cmd += " " + shell_quote(a);
  cmd += " < /dev/null " + (stdout_to.empty() ? "> " + shell_quote(out.string()) : stdout_to) + " 2> " +
         shell_quote(err.string());
  const int status = std::system(cmd.c_str());
  Outcome o;
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  o.out = test::read_text(out);
  o.err = test::read_text(err);
  fs::remove(out);
  fs::remove(err);
  return o;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Column name -> values, from a trajectory.csv.
std::map<std::string, std::vector<double>> read_csv(const fs::path& path) {
  const auto lines = lines_of(test::read_text(path));
  std::vector<std::string> names;
  std::istringstream header(lines.at(0));
  for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  std::map<std::string, std::vector<double>> columns;
  for (size_t i = 1; i < lines.size(); ++i) {
    std::istringstream row(lines[i]);
    std::string cell;
    for (const auto& name : names) {
      std::getline(row, cell, ',');
      columns[name].push_back(cell.empty() ? std::nan("") : std::strtod(cell.c_str(), nullptr));
    }
  }
  return columns;
}

// Every file under `dir` with its bytes and modification time.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    struct stat st {};
    ::stat(e.path().c_str(), &st);
    files[e.path().string()] = test::read_text(e.path()) + "@" + std::to_string(st.st_mtim.tv_sec) + "." +
                               std::to_string(st.st_mtim.tv_nsec);
  }
  return files;
}

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
      {{"sweep", "--range", "0.1:0.001:5"}, 2, "--range: timestep range must run from a positive timestep up to a larger one"},
      {{"sweep", "--range", "0.001:0.1"}, 2, "--range must be FROM:TO:COUNT, got '0.001:0.1'"},
      {{"sweep", "--seed", "1"}, 2, "--seed is not a sweep option"},
      {{"--threads", "2"}, 2, "--threads belongs to the sweep command"},
  };
  for (const BadInput& c : cases) {
    std::vector<std::string> args = c.args;
    if (std::find(args.begin(), args.end(), "--out") == args.end()) args.insert(args.end(), {"--out", "out"});
    const Outcome o = sim_loop(dir.path(), args);
    SCOPED_TRACE(c.args.front() + " " + (c.args.size() > 1 ? c.args[1] : "") + " " + (c.args.size() > 2 ? c.args[2] : ""));
    EXPECT_EQ(o.exit_code, c.exit_code);
    EXPECT_EQ(o.err.rfind("sim_loop: ", 0), 0u) << o.err;
    EXPECT_NE(o.err.find(c.message_part), std::string::npos) << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << "one line: " << o.err;
    EXPECT_EQ(snapshot(dir.path()), before) << "outputs changed";
  }
  EXPECT_FALSE(fs::exists(dir.path() / "MUJOCO_LOG.TXT"));
}

// sim_loop started in the background, so that a test can signal it.
class Background {
 public:
  Background(const fs::path& cwd, const std::vector<std::string>& args) : cwd_(cwd) {
    std::vector<std::string> argv_text = {SIM_LOOP_EXE};
    argv_text.insert(argv_text.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_text) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addchdir_np(&actions, cwd.c_str());
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 1, ".stdout", O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, ".stderr", O_WRONLY | O_CREAT | O_TRUNC, 0644);
    // As a terminal's shell starts it: SIGINT and SIGTERM not ignored, even
    // if this test runs as a background job (which ignores SIGINT).
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    sigset_t defaults;
    sigemptyset(&defaults);
    sigaddset(&defaults, SIGINT);
    sigaddset(&defaults, SIGTERM);
    posix_spawnattr_setsigdefault(&attributes, &defaults);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF);
    if (posix_spawn(&pid_, SIM_LOOP_EXE, &actions, &attributes, argv.data(), environ) != 0) pid_ = -1;
    posix_spawnattr_destroy(&attributes);
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Background() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Background(const Background&) = delete;
  Background& operator=(const Background&) = delete;

  [[nodiscard]] bool started() const { return pid_ > 0; }
  // Once it has printed its banner (its signal handlers are in place by
  // then) and `delay` more has passed, sends `sig` and waits up to 10 s for
  // the process to end: its stdout, stderr and exit code (-1 if a signal
  // killed it, -2 if it was still running, and then killed), and in
  // `seconds` how long it took from the signal.
  Outcome signal_after(std::chrono::duration<double> delay, int sig, double* seconds) {
    const auto limit = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (test::read_text(cwd_ / ".stdout").empty() && std::chrono::steady_clock::now() < limit) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    std::this_thread::sleep_for(delay);
    ::kill(pid_, sig);
    Outcome o;
    wait(std::chrono::seconds(10), seconds, &o);
    return o;
  }

 private:
  void wait(std::chrono::duration<double> limit, double* seconds, Outcome* o) {
    const auto start = std::chrono::steady_clock::now();
    int status = 0;
    int code = -2;
    for (;;) {
      const pid_t done = ::waitpid(pid_, &status, WNOHANG);
      if (done == pid_) {
        code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        pid_ = -1;
        break;
      }
      if (std::chrono::steady_clock::now() - start > limit) break;
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
    *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
      pid_ = -1;
    }
    o->exit_code = code;
    o->out = test::read_text(cwd_ / ".stdout");
    o->err = test::read_text(cwd_ / ".stderr");
    fs::remove(cwd_ / ".stdout");
    fs::remove(cwd_ / ".stderr");
  }

  fs::path cwd_;
  pid_t pid_ = -1;
};

// The names in `dir`, sorted.
std::set<std::string> names_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

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
    EXPECT_NE(o.err.find("small/trajectory.csv: cannot write (No space left on device)"), std::string::npos)
        << o.err;
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
  const Outcome o = sim_loop(dir.path(), {"--smoke", "--plot", "--out", "out"},
                             "SIMLOOP_PYTHON=" + shell_quote(fake.string()));
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
  for (const std::vector<std::string> args : {std::vector<std::string>{"--model", "big.xml", "--out", "s"},
                                              std::vector<std::string>{"sweep", "--model", "big.xml", "--out", "s"}}) {
    const Outcome o = sim_loop(dir.path(), args, "ulimit -v 300000 &&");
    EXPECT_EQ(o.exit_code, 2);
    EXPECT_EQ(o.err, "sim_loop: --model: big.xml: Error: engine error: Could not allocate memory\n");
    EXPECT_FALSE(fs::exists(dir.path() / "s" / "sweep.csv"));
    EXPECT_FALSE(fs::exists(dir.path() / "s" / "metrics.json"));
  }
}

}  // namespace
