// The record every run leaves: the chapter's RunResult is one, labelled as
// the chapter's scenario would label it, and the outputs made from a record
// are the same whichever loop made it.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>

#include "simloop/errors.hpp"
#include "simloop/output.hpp"
#include "simloop/run.hpp"
#include "simloop/scenario_run.hpp"

namespace {

bool same_doubles(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

TEST(RunRecord, TheChaptersRunIsLabelledAsTheChaptersScenarioAndEndsInTheSameState) {
  const simloop::Model model = simloop::pusher_scene();
  simloop::RunConfig config;
  config.seed = 3;
  config.steps = 600;
  config.rng = simloop::ShoveRng::kNumpy;
  const simloop::RunResult chapter = simloop::run(model, config);
  simloop::ScenarioConfig same;
  same.seed = 3;
  same.steps = 600;
  same.rng = simloop::ShoveRng::kNumpy;
  const simloop::RunRecord scenario = simloop::run_scenario(model, simloop::Scenario::chapter(), same);

  EXPECT_EQ(chapter.name, scenario.name);
  EXPECT_EQ(chapter.seed, scenario.seed);
  EXPECT_EQ(chapter.rng, scenario.rng);
  EXPECT_EQ(chapter.perturb, scenario.perturb);
  EXPECT_EQ(chapter.disturbed_bodies, scenario.disturbed_bodies);
  ASSERT_EQ(chapter.schedule.forces.size(), 1u);
  ASSERT_EQ(scenario.schedule.forces.size(), 1u);
  EXPECT_EQ(chapter.schedule.steps, scenario.schedule.steps);
  EXPECT_EQ(chapter.schedule.forces[0].start, scenario.schedule.forces[0].start);
  EXPECT_EQ(chapter.schedule.forces[0].end, scenario.schedule.forces[0].end);
  EXPECT_EQ(chapter.schedule.forces[0].wrench, scenario.schedule.forces[0].wrench);
  // The same physics, bit for bit, whichever recorder watched it.
  EXPECT_TRUE(same_doubles(chapter.final_state, scenario.final_state));
  EXPECT_EQ(chapter.rows, chapter.trajectory.rows());
  ASSERT_EQ(chapter.columns.size(), static_cast<size_t>(chapter.trajectory.columns()));
  EXPECT_EQ(chapter.columns[simloop::ChapterColumns::kBoxZ].name, "box_z");
  EXPECT_TRUE(same_doubles(
      chapter.final_row, std::vector<double>(chapter.trajectory.row(chapter.rows - 1),
                                             chapter.trajectory.row(chapter.rows - 1) + chapter.trajectory.columns())));
}

TEST(RunRecord, TheBaselineHasNoDisturbanceInItsRecord) {
  simloop::RunConfig config;
  config.steps = 100;
  config.perturb = false;
  const simloop::RunResult result = simloop::run(simloop::pusher_scene(), config);
  EXPECT_TRUE(result.schedule.forces.empty());
  EXPECT_TRUE(result.disturbed_bodies.empty());
  EXPECT_FALSE(result.perturb);
}

TEST(RunRecord, TheChaptersMetricsAreItsOwnAndAsARecordItsScenarios) {
  simloop::RunConfig config;
  config.steps = 200;
  const simloop::RunResult result = simloop::run(simloop::pusher_scene(), config);
  EXPECT_EQ(simloop::metrics_json(result), simloop::metrics_json(result.metrics));
  const simloop::RunRecord& record = result;
  const std::string as_record = simloop::metrics_json(record);
  EXPECT_NE(as_record.find("\"scenario\": \"ch0.1-sim-loop\""), std::string::npos) << as_record;
  EXPECT_NE(as_record.find("\"body\": \"box\""), std::string::npos) << as_record;
  EXPECT_EQ(simloop::summary_text(result).rfind("stepped 200 steps", 0), 0u);
  EXPECT_EQ(simloop::summary_text(record).rfind("scenario ch0.1-sim-loop: stepped 200 steps", 0), 0u);
}

TEST(RunRecord, WritingARunWhoseRowsWereStreamedIsRefused) {
  simloop::RunConfig config;
  config.steps = 50;
  const simloop::Model model = simloop::pusher_scene();
  simloop::Data data(model);
  simloop::DiscardRows discard;
  const simloop::RunResult streamed = simloop::run(model, config, data, &discard);
  EXPECT_EQ(streamed.trajectory.rows(), 0);
  EXPECT_EQ(streamed.rows, 51);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "simloop_record_test_streamed";
  std::filesystem::remove_all(dir);
  EXPECT_THROW((void)simloop::write_outputs(streamed, dir), simloop::InvalidArgument);
  EXPECT_FALSE(std::filesystem::exists(dir / "metrics.json"));
  std::filesystem::remove_all(dir);
}

}  // namespace
