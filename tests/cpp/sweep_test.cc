// sweep: the chapter's baseline at many timesteps, where Break It begins;
// its table, its default timesteps, its thread count, its bad input.
#include "simloop/sweep.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
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

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(Sweep, IsTheChaptersScenarioSweptSeenAsTheChapter) {
  // The chapter's sweep is sweep_scenario on chapter_scenario(), the
  // baseline with the energy audit on: each point is the engine's box
  // figures, and what the chapter's own run at that timestep shows, bit for
  // bit. 0.002 s is stable, 0.005 s hops, 0.5 s sinks and warns.
  const std::vector<double> dts = {0.002, 0.005, 0.5};
  const simloop::SweepResult chapter = simloop::sweep(scene(), dts, 4.0, 2);
  simloop::ScenarioConfig baseline;
  baseline.perturb = false;
  baseline.audit_energy = true;
  const simloop::ScenarioSweepResult swept =
      simloop::sweep_scenario(scene(), simloop::chapter_scenario(scene()), dts, 4.0, baseline, 2);
  ASSERT_EQ(swept.bodies, std::vector<std::string>{"box"});
  ASSERT_EQ(chapter.points.size(), 3u);
  ASSERT_EQ(swept.points.size(), 3u);
  for (size_t i = 0; i < dts.size(); ++i) {
    const simloop::SweepPoint& p = chapter.points[i];
    const simloop::ScenarioSweepPoint& q = swept.points[i];
    simloop::RunConfig config;
    config.timestep = dts[i];
    config.steps = simloop::sweep_steps(4.0, dts[i]);
    config.perturb = false;
    config.audit_energy = true;
    const simloop::RunResult run = simloop::run(scene(), config);
    double peak_z = -INFINITY, max_abs_y = 0.0;
    for (std::int64_t r = 0; r < run.trajectory.rows(); ++r) {
      peak_z = std::max(peak_z, run.trajectory.row(r)[simloop::ChapterColumns::kBoxZ]);
      max_abs_y = std::max(max_abs_y, std::fabs(run.trajectory.row(r)[simloop::ChapterColumns::kBoxY]));
    }
    std::int64_t warnings = 0;
    for (const simloop::Warning& w : run.warnings) warnings += w.count;
    const double* last = run.final_row.data();
    EXPECT_EQ(p.timestep, q.timestep);
    EXPECT_EQ(p.steps, q.steps);
    EXPECT_EQ(p.steps, run.metrics.steps);
    EXPECT_TRUE(same_bits(p.peak_box_z, q.peak_z[0]) && same_bits(p.peak_box_z, peak_z)) << p.timestep;
    EXPECT_TRUE(same_bits(p.max_abs_box_y, q.max_abs_y[0]) && same_bits(p.max_abs_box_y, max_abs_y)) << p.timestep;
    const double final_box[] = {p.final_box_x, p.final_box_y, p.final_box_z};
    EXPECT_EQ(std::memcmp(final_box, q.final_positions[0].data(), sizeof final_box), 0) << p.timestep;
    EXPECT_EQ(std::memcmp(final_box, last + simloop::ChapterColumns::kBoxX, sizeof final_box), 0) << p.timestep;
    EXPECT_TRUE(same_bits(p.final_pusher_x, last[simloop::ChapterColumns::kPusherX])) << p.timestep;
    EXPECT_EQ(p.warnings, q.mujoco_warnings + q.diverged);
    EXPECT_EQ(p.warnings, warnings);
    EXPECT_EQ(std::memcmp(&p.energy, &run.energy, sizeof p.energy), 0) << p.timestep;
    EXPECT_EQ(std::memcmp(&p.energy, &q.energy, sizeof p.energy), 0) << p.timestep;
  }
  EXPECT_GT(chapter.points[2].warnings, 0);
  EXPECT_EQ(chapter.edge_index, 0);
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
