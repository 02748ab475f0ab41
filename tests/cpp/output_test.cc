#include "simloop/output.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "simloop/control.hpp"
#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/run.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

// Both expected texts were written by CPython 3.11:
// json.dumps(metrics, indent=2, sort_keys=True) + "\n".
TEST(MetricsJson, MatchesPythonJsonDumps) {
  simloop::Metrics m;
  m.steps = 300;
  m.seed = std::numeric_limits<std::uint64_t>::max();
  m.perturb = false;
  m.box_final_pos = {4.849876, -0.0, 1e-05};
  m.box_final_speed = 0.0;
  m.pusher_final_x = 4.75995;
  m.lateral_drift = 0.000123;
  m.shove_moved_box = false;
  EXPECT_EQ(simloop::metrics_json(m),
            "{\n  \"box_final_pos\": [\n    4.849876,\n    -0.0,\n    1e-05\n  ],\n  \"box_final_speed\": 0.0,\n"
            "  \"lateral_drift\": 0.000123,\n  \"perturb\": false,\n  \"pusher_final_x\": 4.75995,\n"
            "  \"seed\": 18446744073709551615,\n  \"shove_moved_box\": false,\n  \"steps\": 300\n}\n");
}

TEST(MetricsJson, NonFiniteAsPythonWritesThem) {
  simloop::Metrics m;
  m.steps = 2000;
  m.seed = 0;
  m.perturb = true;
  m.box_final_pos = {std::nan(""), INFINITY, -INFINITY};
  m.box_final_speed = 12.0;
  m.pusher_final_x = -3.5;
  m.lateral_drift = 0.133;
  m.shove_moved_box = true;
  EXPECT_EQ(simloop::metrics_json(m),
            "{\n  \"box_final_pos\": [\n    NaN,\n    Infinity,\n    -Infinity\n  ],\n  \"box_final_speed\": 12.0,\n"
            "  \"lateral_drift\": 0.133,\n  \"perturb\": true,\n  \"pusher_final_x\": -3.5,\n  \"seed\": 0,\n"
            "  \"shove_moved_box\": true,\n  \"steps\": 2000\n}\n");
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

TEST(TrajectoryCsv, RoundTripsEveryDoubleExactly) {
  const simloop::Model model = simloop::pusher_scene();
  simloop::RunConfig config;
  config.steps = 400;
  config.record_every = 3;
  const simloop::RunResult r = simloop::run(model, config);
  const simloop::Trajectory& t = r.trajectory;
  std::istringstream csv(simloop::trajectory_csv(t));
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line,
            "step,time,ctrl,shove_x,shove_y,shove_z,box_x,box_y,box_z,box_qw,box_qx,box_qy,box_qz,"
            "box_vx,box_vy,box_vz,box_wx,box_wy,box_wz,pusher_x,pusher_vx,ncon");
  std::int64_t row = 0;
  while (std::getline(csv, line)) {
    const auto cells = split(line);
    ASSERT_EQ(cells.size(), static_cast<size_t>(t.columns())) << line;
    EXPECT_EQ(cells[0], std::to_string(static_cast<long long>(t.at(row, 0)))) << "step is a whole number";
    for (int c = 0; c < t.columns(); ++c) {
      const double expected = t.at(row, c);
      if (std::isnan(expected)) {
        EXPECT_TRUE(cells[c].empty()) << "row " << row << " column " << c;
        continue;
      }
      const double back = std::strtod(cells[c].c_str(), nullptr);
      ASSERT_EQ(std::memcmp(&back, &expected, sizeof back), 0) << "row " << row << " column " << c;
    }
    ++row;
  }
  EXPECT_EQ(row, t.rows());
}

TEST(Outputs, WriteBothFilesAndReplaceOldOnes) {
  test::TempDir dir;
  const fs::path out = dir.path() / "nested" / "out";
  const simloop::Model model = simloop::pusher_scene();
  simloop::RunConfig config;
  config.smoke = true;
  const simloop::RunResult r = simloop::run(model, config);
  fs::create_directories(out);
  test::write_text(out / "metrics.json", "old");
  const simloop::OutputFiles files = simloop::write_outputs(r, out);
  EXPECT_EQ(test::read_text(files.metrics), simloop::metrics_json(r.metrics));
  EXPECT_EQ(test::read_text(files.trajectory), simloop::trajectory_csv(r.trajectory));
  // No temporary files are left behind.
  int entries = 0;
  for (const auto& e : fs::directory_iterator(out)) {
    (void)e;
    ++entries;
  }
  EXPECT_EQ(entries, 2);
  struct stat st {};
  ASSERT_EQ(::stat(files.metrics.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0644u);
}

TEST(Outputs, AFileInTheWayIsAnErrorAndIsLeftAlone) {
  test::TempDir dir;
  const fs::path blocker = dir.path() / "out";
  test::write_text(blocker, "precious");
  EXPECT_THROW(simloop::prepare_output_dir(blocker), simloop::IoError);
  EXPECT_THROW(simloop::prepare_output_dir(blocker / "sub"), simloop::IoError);
  try {
    simloop::prepare_output_dir(blocker);
  } catch (const simloop::IoError& e) {
    EXPECT_NE(std::string(e.what()).find(blocker.string()), std::string::npos) << e.what();
  }
  EXPECT_EQ(test::read_text(blocker), "precious");
}

TEST(Outputs, UnwritableDirectoryIsAnError) {
  // /proc/self refuses new entries even to root.
  EXPECT_THROW(simloop::prepare_output_dir("/proc/self/simloop-out"), simloop::IoError);
  EXPECT_THROW(simloop::write_file_atomically("/proc/self/simloop-file", "x"), simloop::IoError);
}

TEST(Outputs, FailedWriteKeepsTheOldFile) {
  test::TempDir dir;
  const fs::path target = dir.path() / "metrics.json";
  test::write_text(target, "old contents");
  // A directory where the temporary file's rename target is cannot be
  // replaced: rename(file, non-empty dir) fails.
  const fs::path dir_target = dir.path() / "blocked";
  fs::create_directories(dir_target / "inside");
  EXPECT_THROW(simloop::write_file_atomically(dir_target, "new"), simloop::IoError);
  EXPECT_TRUE(fs::is_directory(dir_target / "inside"));
  EXPECT_EQ(test::read_text(target), "old contents");
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    (void)e;
    ++entries;
  }
  EXPECT_EQ(entries, 2) << "a temporary file was left behind";
}

TEST(Summary, SaysWhatTheChapterSays) {
  const simloop::Model model = simloop::pusher_scene();
  simloop::RunConfig config;
  config.smoke = true;
  const simloop::RunResult shoved = simloop::run(model, config);
  const std::string text = simloop::summary_text(shoved);
  EXPECT_EQ(text.rfind("stepped 300 steps of 0.002 s -> 0.60 s of sim time\n", 0), 0u) << text;
  EXPECT_NE(text.find("shove: +7.0 N in y for 50 steps -> "), std::string::npos) << text;
  // The summary names the generator that drew the shove.
  EXPECT_NE(text.find(" of sideways drift (drawn by std::mt19937_64 from seed 0)\n"), std::string::npos) << text;
  config.rng = simloop::ShoveRng::kNumpy;
  const std::string numpy = simloop::summary_text(simloop::run(model, config));
  EXPECT_NE(numpy.find("shove: +9.8 N in y for 50 steps -> "), std::string::npos) << numpy;
  EXPECT_NE(numpy.find(" of sideways drift (drawn by numpy default_rng (PCG64) from seed 0)\n"), std::string::npos)
      << numpy;
  config.rng = simloop::ShoveRng::kMt19937_64;
  config.perturb = false;
  const std::string baseline = simloop::summary_text(simloop::run(model, config));
  EXPECT_NE(baseline.find("no shove (baseline run)\n"), std::string::npos) << baseline;
  EXPECT_EQ(baseline.find("warning"), std::string::npos) << baseline;
}

TEST(Summary, OnlyMujocosBadValueWarningsGetTheResetNote) {
  // MuJoCo resets the state after its bad-value warnings; simloop's own
  // divergence warning is no such reset, and must not claim one.
  simloop::RunConfig config;
  config.steps = 100;
  simloop::RunResult result = simloop::run(simloop::pusher_scene(), config);
  result.warnings = {simloop::Warning{"simloop_DIVERGED", 3, 40, "body \"box\" went through the floor"}};
  std::string text = simloop::summary_text(result);
  EXPECT_NE(text.find("simloop warning simloop_DIVERGED: raised 3 times, first in step 40: body"), std::string::npos)
      << text;
  EXPECT_EQ(text.find("MuJoCo resets the state"), std::string::npos) << text;
  result.warnings.push_back(simloop::Warning{"mjWARN_BADQACC", 1, 41, "Nan, Inf or huge value in QACC"});
  text = simloop::summary_text(result);
  EXPECT_NE(text.find("MuJoCo warning mjWARN_BADQACC: raised 1 time, first in step 41"), std::string::npos) << text;
  EXPECT_NE(text.find("MuJoCo resets the state and carries on"), std::string::npos) << text;
}

TEST(Summary, ACutShortShoveSaysHowManyStepsItActed) {
  const simloop::Model model = simloop::pusher_scene();
  simloop::RunConfig config;
  config.steps = 60;  // the shove starts at step 30, so the run ends 30 steps into it
  const std::string text = simloop::summary_text(simloop::run(model, config));
  EXPECT_NE(text.find("shove: +7.0 N in y for 30 steps (of 50: the run ended first) -> "), std::string::npos) << text;
  config.steps = 1;
  const std::string one = simloop::summary_text(simloop::run(model, config));
  EXPECT_NE(one.find(" for 1 step (of 50: the run ended first) -> "), std::string::npos) << one;
  config.steps = 130;  // ends on the shove's last step: all of it acted
  const std::string whole = simloop::summary_text(simloop::run(model, config));
  EXPECT_NE(whole.find(" for 50 steps -> "), std::string::npos) << whole;
}

// The names in `dir`, sorted.
std::set<std::string> names_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

// The commands' streamed trajectory.csv is the file the in-memory result
// gives, byte for byte, for runs that flush many times and runs that never do.
TEST(Outputs, StreamedTrajectoryIsTheInMemoryOneByteForByte) {
  const simloop::Model model = simloop::pusher_scene();
  struct Case {
    std::int64_t steps;
    std::int64_t record_every;
    bool audit;
  };
  // 20000 steps: about 6.6 MB of CSV, several flushes of TrajectoryCsvSink.
  for (const Case c : {Case{300, 1, false}, Case{400, 3, false}, Case{1, 1, false}, Case{5, 10, false},
                       Case{1000, 7, true}, Case{20000, 1, true}, Case{20000, 1, false}}) {
    SCOPED_TRACE("steps " + std::to_string(c.steps) + " record_every " + std::to_string(c.record_every) +
                 (c.audit ? " audit" : ""));
    simloop::RunConfig config;
    config.seed = 5;
    config.steps = c.steps;
    config.record_every = c.record_every;
    config.audit_energy = c.audit;
    const simloop::RunResult kept = simloop::run(model, config);
    test::TempDir dir;
    simloop::OutputWriter writer(dir.path());
    simloop::Data workspace(model);
    const simloop::RunResult streamed = simloop::run(model, config, workspace, &writer.trajectory());
    EXPECT_EQ(streamed.trajectory.rows(), 0) << "the rows went to the sink";
    EXPECT_EQ(streamed.rows, kept.trajectory.rows());
    const simloop::OutputFiles files = writer.commit(streamed.metrics);
    EXPECT_TRUE(test::read_text(files.trajectory) == simloop::trajectory_csv(kept.trajectory));
    EXPECT_EQ(test::read_text(files.metrics), simloop::metrics_json(kept.metrics));
    EXPECT_EQ(names_in(dir.path()), (std::set<std::string>{"metrics.json", "trajectory.csv"}));
  }
}

// Stand-ins for an earlier run's outputs in `dir`.
void write_old_outputs(const fs::path& dir) {
  test::write_text(dir / "metrics.json", "old metrics");
  test::write_text(dir / "trajectory.csv", "old trajectory");
}

simloop::RunResult smoke_result() {
  simloop::RunConfig config;
  config.smoke = true;
  return simloop::run(simloop::pusher_scene(), config);
}

// After a failed write_outputs: the old files as they were, nothing else.
void expect_old_outputs_only(const fs::path& dir, const std::set<std::string>& names) {
  EXPECT_EQ(names_in(dir), names) << "a temporary or backup file was left behind, or a file went missing";
  // (EXPECT_TRUE: a failure would print a whole trajectory otherwise.)
  if (fs::is_regular_file(dir / "metrics.json")) {
    EXPECT_TRUE(test::read_text(dir / "metrics.json") == "old metrics") << "metrics.json was replaced";
  }
  if (fs::is_regular_file(dir / "trajectory.csv")) {
    EXPECT_TRUE(test::read_text(dir / "trajectory.csv") == "old trajectory") << "trajectory.csv was replaced";
  }
}

TEST(Outputs, BothOrNeitherAreReplacedWhenOneIsADirectory) {
  const simloop::RunResult r = smoke_result();
  for (const char* blocked : {"metrics.json", "trajectory.csv"}) {
    SCOPED_TRACE(blocked);
    test::TempDir dir;
    write_old_outputs(dir.path());
    fs::remove(dir.path() / blocked);
    fs::create_directories(dir.path() / blocked / "inside");
    try {
      (void)simloop::write_outputs(r, dir.path());
      ADD_FAILURE() << "no error";
    } catch (const simloop::IoError& e) {
      EXPECT_NE(std::string(e.what()).find(blocked), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
    }
    expect_old_outputs_only(dir.path(), {"metrics.json", "trajectory.csv"});
    EXPECT_TRUE(fs::is_directory(dir.path() / blocked / "inside"));
  }
}

TEST(Outputs, BothOrNeitherAreReplacedWhenMetricsIsImmutable) {
  const simloop::RunResult r = smoke_result();
  test::TempDir dir;
  write_old_outputs(dir.path());
  const std::string metrics = (dir.path() / "metrics.json").string();
  if (std::system(("chattr +i '" + metrics + "' 2>/dev/null").c_str()) != 0) {
    GTEST_SKIP() << "chattr +i is not available here (needs root and a filesystem that supports it)";
  }
  bool threw = false;
  try {
    (void)simloop::write_outputs(r, dir.path());
  } catch (const simloop::IoError& e) {
    threw = true;
    EXPECT_NE(std::string(e.what()).find("metrics.json: cannot replace"), std::string::npos) << e.what();
  }
  EXPECT_EQ(std::system(("chattr -i '" + metrics + "'").c_str()), 0);
  EXPECT_TRUE(threw);
  expect_old_outputs_only(dir.path(), {"metrics.json", "trajectory.csv"});
}

// A file-size limit (ulimit -f) stands in for a full disk: write() fails with
// EFBIG once SIGXFSZ is ignored.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    previous_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    ::getrlimit(RLIMIT_FSIZE, &previous_);
    rlimit limit = previous_;
    limit.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &previous_);
    std::signal(SIGXFSZ, previous_handler_);
  }

 private:
  rlimit previous_{};
  void (*previous_handler_)(int) = nullptr;
};

TEST(Outputs, AFullDiskLeavesTheOldFilesAndNoTemporaryOnes) {
  const simloop::RunResult r = smoke_result();  // its trajectory.csv: about 100 kB
  test::TempDir dir;
  write_old_outputs(dir.path());
  for (int attempt = 0; attempt < 3; ++attempt) {
    const FileSizeLimit limit(50'000);
    try {
      (void)simloop::write_outputs(r, dir.path());
      ADD_FAILURE() << "no error";
    } catch (const simloop::IoError& e) {
      EXPECT_NE(std::string(e.what()).find("trajectory.csv: cannot write (File too large)"), std::string::npos)
          << e.what();
    }
  }
  expect_old_outputs_only(dir.path(), {"metrics.json", "trajectory.csv"});
}

TEST(Outputs, AFullDiskWhileStreamingLeavesTheOldFilesAndNoTemporaryOnes) {
  test::TempDir dir;
  write_old_outputs(dir.path());
  for (const std::int64_t steps : {std::int64_t{2000}, std::int64_t{20000}}) {
    SCOPED_TRACE(steps);
    const FileSizeLimit limit(50'000);
    simloop::RunConfig config;
    config.steps = steps;
    const simloop::Model model = simloop::pusher_scene();
    simloop::Data workspace(model);
    simloop::OutputWriter writer(dir.path());
    // The sink writes every ~1 MB: 2000 rows (~0.7 MB) meet the limit at
    // commit, 20000 rows (~6.6 MB) during the run.
    EXPECT_THROW((void)writer.commit(simloop::run(model, config, workspace, &writer.trajectory()).metrics),
                 simloop::IoError);
  }
  expect_old_outputs_only(dir.path(), {"metrics.json", "trajectory.csv"});
}

TEST(Outputs, AnInterruptedWriterLeavesTheOldFilesAndNoTemporaryOnes) {
  const simloop::Model model = simloop::pusher_scene();
  test::TempDir dir;
  write_old_outputs(dir.path());
  simloop::RunConfig config;
  config.steps = 100000;
  simloop::Data workspace(model);
  {
    // Stopped mid-run: the loop throws, the writer goes with the stack.
    simloop::RunControl control;
    simloop::OutputWriter writer(dir.path());
    control.request_stop();
    EXPECT_THROW((void)simloop::run(model, config, workspace, &writer.trajectory(), &control), simloop::Interrupted);
  }
  expect_old_outputs_only(dir.path(), {"metrics.json", "trajectory.csv"});
  {
    // Stopped after the run, before the commit: nothing is put in place.
    config.steps = 100;
    simloop::RunControl control;
    simloop::OutputWriter writer(dir.path());
    const simloop::RunResult r = simloop::run(model, config, workspace, &writer.trajectory(), &control);
    control.request_stop();
    EXPECT_THROW((void)writer.commit(r.metrics, &control), simloop::Interrupted);
  }
  expect_old_outputs_only(dir.path(), {"metrics.json", "trajectory.csv"});
}

TEST(Outputs, NewOutputsWhereThereWereNoneAndNoBackupsLeft) {
  const simloop::RunResult r = smoke_result();
  test::TempDir dir;
  (void)simloop::write_outputs(r, dir.path());
  (void)simloop::write_outputs(r, dir.path());  // over the first: backups made, then removed
  EXPECT_EQ(names_in(dir.path()), (std::set<std::string>{"metrics.json", "trajectory.csv"}));
  struct stat st {};
  ASSERT_EQ(::stat((dir.path() / "trajectory.csv").c_str(), &st), 0);
  EXPECT_EQ(st.st_nlink, 1u) << "a backup link remains";
  EXPECT_EQ(test::read_text(dir.path() / "trajectory.csv"), simloop::trajectory_csv(r.trajectory));
}

}  // namespace
