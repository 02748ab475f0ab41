#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/output.hpp"
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
  const simloop::Model model = simloop::Model::pusher_scene();
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
  const simloop::Model model = simloop::Model::pusher_scene();
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
  const simloop::Model model = simloop::Model::pusher_scene();
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

}  // namespace
