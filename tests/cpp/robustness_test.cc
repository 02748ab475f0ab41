// The library under hostile input (issue 8): sizes that overflow,
// trajectories that cannot fit, XML the loader cannot take, sweep points
// that cannot be run as asked, errors that must say what was being done, and
// blow-ups that must not pass in silence. Scarce resources (memory inside
// MuJoCo, threads) are in robustness_resources_test.cc.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "chapter_detail.hpp"
#include "model_detail.hpp"
#include "mujoco_guard.hpp"
#include "robustness_util.hpp"
#include "run_detail.hpp"
#include "simloop/batch.hpp"
#include "simloop/errors.hpp"
#include "simloop/output.hpp"
#include "simloop/run.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/sweep.hpp"
#include "test_util.hpp"

namespace {

using simloop::ChapterColumns;
using simloop::Trajectory;
using test::config_with;
using test::scene;

constexpr std::int64_t kInt64Max = std::numeric_limits<std::int64_t>::max();

// ---- Item 1: sizes without overflow, one range for both faces ----

TEST(Robustness, RowsForDoesNotOverflowAtTheTopOfTheRange) {
  // steps + record_every - 1 overflowed here (UBSan: signed overflow).
  EXPECT_EQ(Trajectory::rows_for(kInt64Max, kInt64Max), 2);
  EXPECT_EQ(Trajectory::rows_for(kInt64Max, kInt64Max - 1), 3);
  EXPECT_EQ(Trajectory::rows_for(kInt64Max, 2), (std::int64_t{1} << 62) + 1);
  EXPECT_EQ(Trajectory::rows_for(simloop::kMaxSteps, 1), simloop::kMaxSteps + 1);
  EXPECT_EQ(Trajectory::rows_for(10, 3), 5);  // steps 0, 3, 6, 9, then the final state
  EXPECT_EQ(Trajectory::rows_for(9, 3), 4);
}

TEST(Robustness, ValidateEnforcesTheDocumentedRanges) {
  EXPECT_EQ(simloop::kMaxSteps, (std::int64_t{1} << 62) - 1);
  EXPECT_EQ(simloop::kMaxRecordEvery, simloop::kMaxSteps);
  EXPECT_NO_THROW(simloop::validate(config_with(simloop::kMaxSteps, simloop::kMaxRecordEvery)));
  EXPECT_EQ(test::error_of([] { simloop::validate(config_with(simloop::kMaxSteps + 1)); }),
            "steps must be at most 4611686018427387903, got 4611686018427387904");
  EXPECT_EQ(test::error_of([] { simloop::validate(config_with(10, kInt64Max)); }),
            "record_every must be at most 4611686018427387903, got 9223372036854775807");
}

// ---- Item 9: a kept trajectory that cannot fit is refused up front ----

TEST(Robustness, AKeptTrajectoryTooLargeIsRefusedSayingHowMuchAndWhatToChange) {
  const std::string message = test::error_of([] { (void)simloop::run(scene(), config_with(10'000'000'000)); });
  EXPECT_EQ(
      message.rfind("steps 10000000000 with record_every 1 would keep 1.6 TiB of trajectory (22 columns) in memory", 0),
      0u)
      << message;
  EXPECT_NE(message.find("raise record_every"), std::string::npos) << message;
  // The same run with a coarser record fits.
  simloop::RunConfig sparse = config_with(10'000'000'000, 1'000'000'000);
  EXPECT_NO_THROW(simloop::check_kept_rows({simloop::kept_rows(sparse)}));
}

TEST(Robustness, ThreadsAreFromZeroToTheMostWeTake) {
  EXPECT_NO_THROW(simloop::check_threads(0));
  EXPECT_NO_THROW(simloop::check_threads(simloop::kMaxThreads));
  EXPECT_EQ(test::error_of([] { simloop::check_threads(simloop::kMaxThreads + 1); }),
            "threads must be from 1 to 4096, or 0 for one per core, got 4097");
  EXPECT_EQ(test::error_of([] { simloop::check_threads(-1); }),
            "threads must be from 1 to 4096, or 0 for one per core, got -1");
  // A batch checks them before any run starts.
  const simloop::Scenario scenario = simloop::Scenario::chapter();
  const simloop::Model scene = simloop::load_scene(scenario);
  EXPECT_THROW((void)simloop::run_scenario_batch(scene, scenario, {simloop::ScenarioConfig{}}, -1),
               simloop::InvalidArgument);
}

TEST(Robustness, TheBudgetIsExactAndBatchesSumTheirRuns) {
  const simloop::RunConfig c = config_with(1000);  // 1001 rows of 22 doubles
  const std::uint64_t bytes = 1001 * 22 * 8;
  const simloop::KeptRows kept = simloop::kept_rows(c);
  EXPECT_EQ(kept.bytes(), bytes);
  simloop::RunConfig audited = c;
  audited.audit_energy = true;
  EXPECT_EQ(simloop::kept_rows(audited).bytes(), 1001u * ChapterColumns::kNumColumns * 8);
  EXPECT_NO_THROW(simloop::check_kept_rows({kept}, bytes));
  EXPECT_THROW(simloop::check_kept_rows({kept}, bytes - 1), simloop::InvalidArgument);
  // Two runs each fit alone, not together.
  EXPECT_NO_THROW(simloop::check_kept_rows({kept}, bytes * 3 / 2));
  const std::string message = test::error_of([&] { simloop::check_kept_rows({kept, kept}, bytes * 3 / 2); });
  EXPECT_NE(message.find("(run 0, the largest of 2 runs) and the others would keep"), std::string::npos) << message;
  // Saturates instead of wrapping.
  EXPECT_EQ(simloop::kept_rows(config_with(simloop::kMaxSteps)).bytes(), std::numeric_limits<std::uint64_t>::max());
}

TEST(Robustness, TheBudgetFollowsTheProcessLimit) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "RLIMIT_AS cannot cap a process under AddressSanitizer";
#endif
  // In a child: lowering RLIMIT_AS lowers the budget to half of it.
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    struct rlimit rl {};
    getrlimit(RLIMIT_AS, &rl);
    rl.rlim_cur = std::uint64_t{8} << 30;
    if (setrlimit(RLIMIT_AS, &rl) != 0) _exit(3);
    _exit(simloop::trajectory_memory_budget() <= (std::uint64_t{4} << 30) ? 0 : 1);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

TEST(Robustness, BatchesRefuseTheirSumUpFrontButNotWhenRowsGoToSinks) {
  const std::vector<simloop::RunConfig> huge(3, config_with(4'000'000'000'000));
  const std::string message = test::error_of([&] { (void)simloop::detail::run_chapter_batch(scene(), huge, {}, 1); });
  EXPECT_NE(message.find("of 3 runs"), std::string::npos) << message;
  // With sinks nothing is kept: the batch starts (and stops when asked).
  struct Discard final : simloop::RowSink {
    void start(int, std::int64_t) override {}
    void write(const double*, std::int64_t) override {}
  } discard;
  simloop::RunControl control;
  control.request_stop();
  EXPECT_THROW((void)simloop::detail::run_chapter_batch(scene(), huge, {&discard, &discard, &discard}, 1, &control),
               simloop::Interrupted);
}

// ---- Item 13: errors say what was being done, on one line ----

TEST(Robustness, MujocoErrorsSayWhatWasBeingDoneOnOneLine) {
  const simloop::Model broken = scene().with_timestep(0.002);
  const_cast<mjModel*>(broken.get())->opt.integrator = 99;  // mj_step raises mju_error
  try {
    (void)simloop::run(broken, simloop::RunConfig{});
    ADD_FAILURE() << "ran";
  } catch (const simloop::MujocoError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("running the model at timestep 0.002 s, in steps 0 to 63: ", 0), 0u) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
  try {
    (void)simloop::Model::from_xml_string("<mujoco><worldbody><body></mujoco>", "broken.xml");
    ADD_FAILURE() << "loaded";
  } catch (const simloop::MujocoError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("broken.xml: ", 0), 0u) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;  // MuJoCo's parser message spans lines
  }
  EXPECT_EQ(simloop::detail::one_line("a\nb\r\n\nc  \n"), "a; b; c");
}

// ---- Item 6: XML sizes the in-memory loader cannot take ----

TEST(Robustness, XmlSizesOutsideWhatMujocoTakesAreNamed) {
  using simloop::detail::check_xml_size;
  EXPECT_EQ(test::error_of([] { check_xml_size(0, "<string>"); }), "<string>: the XML is empty (0 bytes)");
  EXPECT_EQ(test::error_of([] { (void)simloop::Model::from_xml_string(""); }), "<string>: the XML is empty (0 bytes)");
  EXPECT_EQ(test::error_of([] { check_xml_size(std::size_t{1} << 31, "big"); }),
            "big: the XML is 2147483648 bytes; MuJoCo's in-memory loader takes at most 2147483647 (write it to a "
            "file and load that)");
  EXPECT_NE(test::error_of([] { check_xml_size(std::size_t{1} << 32, "big"); }), test::kNoInvalidArgument);
  EXPECT_NO_THROW(check_xml_size(std::size_t{1} << 20, "fine"));
  EXPECT_NO_THROW(check_xml_size(2147483647, "fine"));
}

// ---- Item 7: sweep points that cannot be run as asked ----

TEST(Robustness, SweepPointsNeedAFewStepsAndNoMoreThanTheRange) {
  EXPECT_EQ(simloop::sweep_steps(4.0, 0.002), 2000);
  EXPECT_EQ(simloop::sweep_steps(4.0, 1.0), 4);  // the default grid's coarsest point
  EXPECT_EQ(test::error_of([] { (void)simloop::sweep_steps(1e300, 0.01); }),
            "duration 1e+300 s at timestep 0.01 s is 1e+302 steps; a sweep point needs 4 to 4611686018427387903 "
            "steps (duration / timestep, rounded)");
  EXPECT_NE(test::error_of([] { (void)simloop::sweep_steps(4.0, 1e-300); }).find("4e+300 steps"), std::string::npos);
  EXPECT_NE(test::error_of([] { (void)simloop::sweep_steps(9e18, 0.0005); }), test::kNoInvalidArgument);
  EXPECT_NE(test::error_of([] { (void)simloop::sweep_steps(0.001, 0.01); }).find("0.1 steps"), std::string::npos);
  EXPECT_NE(test::error_of([] { (void)simloop::sweep_steps(4.0, 1.2); }), test::kNoInvalidArgument);  // 3.33 -> 3 steps
  // The library's sweep refuses before running anything.
  EXPECT_NE(test::error_of([] { (void)simloop::sweep(scene(), {1e-300, 0.002}); }), test::kNoInvalidArgument);
}

// ---- Item 10: blow-ups are reported, not passed in silence ----

const simloop::Warning* diverged(const simloop::RunResult& r) {
  for (const simloop::Warning& w : r.warnings) {
    if (w.name == "simloop_DIVERGED") return &w;
  }
  return nullptr;
}

simloop::RunResult run_at(double timestep, std::uint64_t seed = 0) {
  simloop::RunConfig c;
  c.timestep = timestep;
  c.seed = seed;
  return simloop::run(scene(), c);
}

TEST(Robustness, HugeTimestepsAreReportedAsDiverged) {
  for (const double dt : {5.0, 1.0}) {
    SCOPED_TRACE(dt);
    const simloop::RunResult r = run_at(dt);
    const simloop::Warning* w = diverged(r);
    ASSERT_NE(w, nullptr) << "box ends at z = " << r.metrics.box_final_pos[2];
    EXPECT_GE(w->count, 1);
    EXPECT_GE(w->first_step, 0);
    EXPECT_LT(w->first_step, r.metrics.steps);
    EXPECT_EQ(w->message.rfind("body \"box\" went through the floor", 0), 0u) << w->message;
    EXPECT_NE(simloop::summary_text(r).find("simloop warning simloop_DIVERGED: raised"), std::string::npos);
  }
}

TEST(Robustness, TheChaptersRunsAndBreakItAreNotDiverged) {
  for (const std::uint64_t seed : {0, 1, 2, 3}) {
    EXPECT_EQ(diverged(run_at(0.002, seed)), nullptr) << seed;
    EXPECT_EQ(diverged(run_at(0.05, seed)), nullptr) << seed;
  }
}

TEST(Robustness, WithoutAFloorThereIsNothingToFallThrough) {
  // The box falls forever (no plane to measure against): not a divergence.
  std::string xml(simloop::pusher_scene_xml());
  const std::string plane = "type=\"plane\"";
  xml.replace(xml.find(plane), plane.size(), "type=\"box\" pos=\"0 0 -1000\"");
  const simloop::Model model = simloop::Model::from_xml_string(xml, "no floor");
  simloop::RunConfig c;
  c.steps = 3000;
  const simloop::RunResult r = simloop::run(model, c);
  EXPECT_LT(r.metrics.box_final_pos[2], -10.0);
  EXPECT_EQ(diverged(r), nullptr);
}

TEST(Robustness, TheSweepCountsADivergenceAsAWarning) {
  const simloop::SweepResult s = simloop::sweep(scene(), {0.002, 1.0}, 8.0, 1);
  ASSERT_EQ(s.points.size(), 2u);
  EXPECT_EQ(s.points[0].warnings, 0);
  EXPECT_GT(s.points[1].warnings, 0);
  EXPECT_FALSE(s.points[1].stable);
}

}  // namespace
