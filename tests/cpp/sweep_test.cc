// sweep: the chapter's baseline at many timesteps, where Break It begins;
// its table, its default timesteps, its thread count, its bad input.
#include "simloop/sweep.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "expected.hpp"
#include "simloop/errors.hpp"
#include "simloop/output.hpp"
#include "simloop/run.hpp"

namespace {

const simloop::Model& scene() {
  static const simloop::Model model = simloop::pusher_scene();
  return model;
}

TEST(Sweep, FindsTheEdgeWhereTheHopBegins) {
  const simloop::SweepResult s = simloop::sweep(scene(), {0.5, 0.04, 0.02, 0.008, 0.005, 0.004, 0.002, 0.001, 0.002});
  ASSERT_EQ(s.points.size(), 8u);  // sorted, duplicate dropped
  EXPECT_EQ(s.points.front().timestep, 0.001);
  EXPECT_EQ(s.points[1].steps, 2000);  // 4 s of sim time
  ASSERT_GE(s.edge_index, 0);
  EXPECT_EQ(s.points[static_cast<size_t>(s.edge_index)].timestep, 0.004);
  // Measured peak z: 0.0535 (0.001 to 0.004), 0.0573 (0.005), 0.0587 (0.008),
  // 0.0654 (0.02), 0.0963 (0.04); at 0.5 the box ends at z -0.37.
  SIMLOOP_EXPECTED(double, settled_peak_z, "sweep.fine_peak_z");
  for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(s.points[i].peak_box_z, settled_peak_z, 0.001);
  EXPECT_GT(s.points[3].peak_box_z, 0.055);
  SIMLOOP_EXPECTED(double, hop_min, "sweep.peak_z_at_0_04_min");
  EXPECT_GT(s.points[6].peak_box_z, hop_min);
  EXPECT_LT(s.points[7].final_box_z, 0.0);
  EXPECT_FALSE(s.points[7].stable);
  const std::string summary = simloop::sweep_summary(s);
  EXPECT_NE(summary.find("largest stable timestep: 0.004 s"), std::string::npos) << summary;
  EXPECT_EQ(summary.rfind("swept 8 timesteps, 4.0 s of sim time each", 0), 0u) << summary;
  const std::string one = simloop::sweep_summary(simloop::sweep(scene(), {0.002}, 0.1));
  EXPECT_EQ(one.rfind("swept 1 timestep, 0.1 s of sim time each", 0), 0u) << one;
}

TEST(Sweep, NamesTheChaptersTimestepsByWhatTheyRanHere) {
  // The sweep's 0.05 s point runs 4 s (80 steps); Break It runs 2000 steps
  // (100 s) and peaks higher: the table must not pass one off as the other.
  const std::string four_s = simloop::sweep_summary(simloop::sweep(scene(), {0.002, 0.004, 0.05}, 4.0));
  EXPECT_NE(four_s.find("yes  <- the chapter's timestep\n"), std::string::npos) << four_s;
  EXPECT_NE(four_s.find("yes  <- edge\n"), std::string::npos) << four_s;
  EXPECT_NE(four_s.find("no  <- Break It's timestep (80 steps here; Break It runs 2000: 100 s)\n"), std::string::npos)
      << four_s;
  const std::string ten_s = simloop::sweep_summary(simloop::sweep(scene(), {0.002, 0.05}, 10.0));
  EXPECT_NE(ten_s.find("yes  <- edge; the chapter's timestep (5000 steps here; the chapter runs 2000: 4 s)\n"),
            std::string::npos)
      << ten_s;
}

TEST(Sweep, TheTableStaysAlignedWhateverTheNumbers) {
  // Timesteps with long decimals, and run counts from 1 to 4 digits (a
  // sweep point needs at least kMinSweepSteps steps).
  const simloop::SweepResult s = simloop::sweep(scene(), {0.0006863, 0.00094201, 0.002, 1.0}, 4.0);
  const std::string summary = simloop::sweep_summary(s);
  std::vector<std::string> lines;
  for (size_t start = 0, end; (end = summary.find('\n', start)) != std::string::npos; start = end + 1) {
    lines.push_back(summary.substr(start, end - start));
  }
  ASSERT_GE(lines.size(), 6u) << summary;
  const std::string& header = lines[1];
  EXPECT_NE(lines[2].find("0.0006863"), std::string::npos) << summary;
  EXPECT_NE(lines[3].find("0.00094201"), std::string::npos) << summary;
  // Every cell is right-aligned under its header's last character; the
  // stable column starts where its header does.
  for (const char* label : {"timestep (s)", "steps", "peak z (m)", "max |y| (m)", "final z (m)", "contacts +work (J)",
                            "unexplained (J)", "warnings"}) {
    const size_t end = header.find(label) + std::string(label).size();
    for (size_t row = 2; row < 6; ++row) {
      ASSERT_GT(lines[row].size(), end) << summary;
      EXPECT_NE(lines[row][end - 1], ' ') << label << " in\n" << summary;
      EXPECT_EQ(lines[row][end], ' ') << label << " in\n" << summary;
    }
  }
  const size_t stable = header.find("stable");
  for (size_t row = 2; row < 6; ++row) {
    const std::string cell = lines[row].substr(stable);
    EXPECT_TRUE(cell.rfind("yes", 0) == 0 || cell.rfind("no", 0) == 0) << summary;
  }
}

TEST(Sweep, TheDefaultTimestepsAreRound) {
  const std::vector<double> dts = simloop::default_sweep_timesteps();
  ASSERT_EQ(dts.size(), 25u);
  EXPECT_EQ(dts.front(), 0.0005);
  EXPECT_EQ(dts.back(), 1.0);
  for (size_t i = 0; i < dts.size(); ++i) {
    // One significant digit, and exactly the double that decimal names.
    char text[32];
    std::snprintf(text, sizeof text, "%.0e", dts[i]);
    EXPECT_EQ(std::strtod(text, nullptr), dts[i]) << text;
    EXPECT_NE(std::string("1234568").find(text[0]), std::string::npos) << text;
    if (i > 0) {
      EXPECT_GT(dts[i], dts[i - 1]);
    }
  }
  // The chapter's default and Break It's timestep are on the grid.
  EXPECT_NE(std::find(dts.begin(), dts.end(), 0.002), dts.end());
  EXPECT_NE(std::find(dts.begin(), dts.end(), 0.05), dts.end());
}

TEST(Sweep, IsTheSameWhateverTheThreadCount) {
  const std::vector<double> dts = simloop::log_spaced(0.001, 0.1, 9);
  EXPECT_EQ(simloop::sweep_csv(simloop::sweep(scene(), dts, 2.0, 1)),
            simloop::sweep_csv(simloop::sweep(scene(), dts, 2.0, 2)));
}

TEST(Sweep, LogSpacingAndBadInput) {
  const auto dts = simloop::log_spaced(0.001, 0.1, 3);
  ASSERT_EQ(dts.size(), 3u);
  EXPECT_EQ(dts[0], 0.001);
  EXPECT_EQ(dts[1], 0.01);
  EXPECT_EQ(dts[2], 0.1);
  EXPECT_THROW((void)simloop::log_spaced(0.1, 0.001, 3), simloop::InvalidArgument);
  EXPECT_THROW((void)simloop::log_spaced(0.0, 0.1, 3), simloop::InvalidArgument);
  EXPECT_THROW((void)simloop::sweep(scene(), {}), simloop::InvalidArgument);
  EXPECT_THROW((void)simloop::sweep(scene(), {0.002, -1.0}), simloop::InvalidArgument);
  EXPECT_THROW((void)simloop::sweep(scene(), {0.002}, 0.0), simloop::InvalidArgument);
}

}  // namespace
