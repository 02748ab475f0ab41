// Results as bytes and back (what Python's pickle and a cluster's workers
// carry): every field with the same bits, and bad bytes refused by name
// without asking for the memory their counts claim.
#include "simloop/record_bytes.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "simloop/chapter_scene.hpp"
#include "simloop/errors.hpp"
#include "simloop/output.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/sweep.hpp"

namespace {

const std::string kDamaged = "the saved fields are damaged or from another simloop version";

// The message `read` throws (InvalidArgument), or "" if it throws nothing.
std::string refusal(const std::function<void()>& read) {
  try {
    read();
  } catch (const simloop::InvalidArgument& e) {
    return e.what();
  }
  return "";
}

bool same_trajectory(const simloop::Trajectory& a, const simloop::Trajectory& b) {
  // memcmp, not ==: the final row's input columns hold NaN.
  return a.rows() == b.rows() && a.columns() == b.columns() &&
         std::memcmp(a.data(), b.data(),
                     sizeof(double) * static_cast<size_t>(a.rows()) * static_cast<size_t>(a.columns())) == 0;
}

simloop::RunResult chapter_run(std::int64_t steps) {
  simloop::RunConfig config;
  config.seed = 5;
  config.steps = steps;
  config.record_every = 7;
  config.audit_energy = true;
  config.rng = simloop::ShoveRng::kNumpy;
  return simloop::run(simloop::pusher_scene(), config);
}

// `bytes` with the sizeof(T) bytes at `at` replaced by `value`'s.
template <class T>
std::string with(std::string bytes, size_t at, T value) {
  return bytes.replace(at, sizeof value, reinterpret_cast<const char*>(&value), sizeof value);
}

TEST(RecordBytes, TheChaptersRunComesBackBitForBit) {
  const simloop::RunResult result = chapter_run(300);
  const std::string bytes = simloop::to_bytes(result);
  const simloop::RunResult back = simloop::run_result_from_bytes(bytes);
  EXPECT_EQ(simloop::to_bytes(back), bytes);  // every field the writer writes, read back
  EXPECT_TRUE(same_trajectory(back.trajectory, result.trajectory));
  ASSERT_EQ(back.final_state.size(), result.final_state.size());
  EXPECT_EQ(std::memcmp(back.final_state.data(), result.final_state.data(), sizeof(double) * back.final_state.size()),
            0);
  EXPECT_EQ(simloop::metrics_json(back), simloop::metrics_json(result));
  EXPECT_EQ(simloop::summary_text(back), simloop::summary_text(result));
  EXPECT_EQ(back.config.rng, simloop::ShoveRng::kNumpy);
  EXPECT_EQ(back.shove.rng, simloop::ShoveRng::kNumpy);
  EXPECT_EQ(back.unrounded_metrics.lateral_drift, result.unrounded_metrics.lateral_drift);
  EXPECT_EQ(back.energy.unexplained, result.energy.unexplained);
  EXPECT_EQ(back.columns.size(), result.columns.size());
  EXPECT_EQ(back.disturbed_bodies, result.disturbed_bodies);
}

TEST(RecordBytes, AScenarioRunComesBackBitForBit) {
  const simloop::Scenario scenario =
      simloop::Scenario::from_toml_file(std::string(SIMLOOP_TEST_SCENES) + "/walker.toml");
  simloop::ScenarioConfig config;
  config.seed = 2;
  config.steps = 400;
  config.record_every = 3;
  simloop::RunRecord record = simloop::run_scenario(simloop::load_scene(scenario), scenario, config);
  record.warnings.push_back({"mjWARN_BADQACC", 2, 17, "Nan, Inf or huge value in QACC at DOF 0. Time = 0.1."});
  const std::string bytes = simloop::to_bytes(record);
  const simloop::RunRecord back = simloop::record_from_bytes(bytes);
  EXPECT_EQ(simloop::to_bytes(back), bytes);
  EXPECT_TRUE(same_trajectory(back.trajectory, record.trajectory));
  EXPECT_EQ(simloop::metrics_json(back), simloop::metrics_json(record));
  EXPECT_EQ(simloop::summary_text(back), simloop::summary_text(record));
  ASSERT_EQ(back.schedule.control_changes.size(), record.schedule.control_changes.size());
  EXPECT_FALSE(back.schedule.control_changes.empty());
  EXPECT_EQ(back.schedule.forces.size(), 1u);
  EXPECT_EQ(back.warnings.at(0).message, record.warnings[0].message);
}

TEST(RecordBytes, ASweepComesBackJudgedAsItWas) {
  const simloop::SweepResult sweep = simloop::sweep(simloop::pusher_scene(), {0.002, 0.005, 0.02}, 1.0, 1);
  const simloop::SweepResult back = simloop::sweep_result_from_bytes(simloop::to_bytes(sweep));
  EXPECT_EQ(simloop::sweep_csv(back), simloop::sweep_csv(sweep));
  EXPECT_EQ(simloop::sweep_summary(back), simloop::sweep_summary(sweep));
  EXPECT_EQ(back.edge_index, sweep.edge_index);
  EXPECT_EQ(back.duration, 1.0);
}

TEST(RecordBytes, ChunksOfASweepJoinAsTheWholeSweep) {
  const simloop::Model scene = simloop::pusher_scene();
  const simloop::SweepResult whole = simloop::sweep(scene, {0.002, 0.005, 0.02}, 1.0, 1);
  const std::vector<simloop::SweepResult> parts = {simloop::sweep(scene, {0.002}, 1.0, 1),
                                                   simloop::sweep(scene, {0.005, 0.02}, 1.0, 1)};
  const simloop::SweepResult joined = simloop::join_sweeps(parts);
  EXPECT_EQ(simloop::sweep_csv(joined), simloop::sweep_csv(whole));
  EXPECT_EQ(joined.edge_index, whole.edge_index);
  EXPECT_NE(refusal([&] {
              (void)simloop::join_sweeps({parts[1], parts[0]});
            }).find("do not ascend at 0.002"),
            std::string::npos);
  simloop::SweepResult longer = parts[1];
  longer.duration = 2.0;
  EXPECT_NE(refusal([&] {
              (void)simloop::join_sweeps({parts[0], longer});
            }).find("durations differ, 1.0 and 2.0"),
            std::string::npos);
  EXPECT_NE(refusal([] { (void)simloop::join_sweeps({}); }), "");
}

TEST(RecordBytes, BytesCutShortOrTooLongAreRefusedAsDamaged) {
  const std::string bytes = simloop::to_bytes(chapter_run(20));
  const std::string damaged = "cannot unpickle a RunResult: " + kDamaged;
  for (size_t n = 0; n < bytes.size(); ++n) {
    ASSERT_EQ(refusal([&] { (void)simloop::run_result_from_bytes(std::string_view(bytes).substr(0, n)); }), damaged)
        << n << " of " << bytes.size() << " bytes";
  }
  EXPECT_EQ(refusal([&] { (void)simloop::run_result_from_bytes(bytes + '\0'); }), damaged);
}

TEST(RecordBytes, AnotherVersionOrKindIsRefusedByName) {
  const std::string bytes = simloop::to_bytes(chapter_run(20));
  EXPECT_EQ(refusal([&] { (void)simloop::run_result_from_bytes(with<std::uint32_t>(bytes, 0, 3)); }),
            "cannot unpickle a RunResult pickled by another simloop version (format 3; this one reads " +
                std::to_string(simloop::kRecordBytesVersion) + ")");
  EXPECT_EQ(refusal([&] { (void)simloop::record_from_bytes(bytes); }),
            "cannot unpickle a ScenarioResult: the saved fields are a RunResult's");
  EXPECT_EQ(refusal([&] { (void)simloop::sweep_result_from_bytes(simloop::to_bytes(simloop::RunRecord{})); }),
            "cannot unpickle a SweepResult: the saved fields are a ScenarioResult's");
  std::string unknown_kind = bytes;
  unknown_kind[4] = 9;
  EXPECT_EQ(refusal([&] { (void)simloop::run_result_from_bytes(unknown_kind); }),
            "cannot unpickle a RunResult: " + kDamaged);
}

TEST(RecordBytes, HugeCountsAndBadValuesAskForNoMemory) {
  // An empty record's bytes: version (4), kind (1), then name's count at 5,
  // seed, rng, perturb (1 byte) at 29, four counts, and the trajectory's
  // rows and columns at 62 and 70.
  const std::string bytes = simloop::to_bytes(simloop::RunRecord{});
  const std::string damaged = "cannot unpickle a ScenarioResult: " + kDamaged;
  const auto read = [](const std::string& b) { return refusal([&] { (void)simloop::record_from_bytes(b); }); };
  ASSERT_EQ(read(bytes), "");
  EXPECT_EQ(read(with<std::uint64_t>(bytes, 5, std::numeric_limits<std::uint64_t>::max())), damaged);
  EXPECT_EQ(read(with<std::uint64_t>(bytes, 30, std::uint64_t{1} << 60)), damaged);  // disturbed bodies
  EXPECT_EQ(read(with<std::uint64_t>(bytes, 38, std::uint64_t{1} << 60)), damaged);  // columns
  EXPECT_EQ(read(with<std::uint64_t>(bytes, 46, std::uint64_t{1} << 60)), damaged);  // final_row's doubles
  EXPECT_EQ(read(with<std::int64_t>(with<int>(bytes, 70, 1000), 62, std::int64_t{1} << 40)), damaged);
  EXPECT_EQ(read(with<std::int64_t>(bytes, 62, -1)), damaged);
  std::string not_a_bool = bytes;
  not_a_bool[29] = 2;
  EXPECT_EQ(read(not_a_bool), damaged);
}

}  // namespace
