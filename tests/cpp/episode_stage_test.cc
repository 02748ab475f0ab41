// Episodes' reset in two calls (stage_reset, commit_reset), around a
// caller's hook that shapes the start: the same bits as reset when nothing
// is written, what is written observed, and a stage never committed
// changing nothing.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "simloop/episode.hpp"
#include "simloop/errors.hpp"
#include "simloop/scenario_run.hpp"

namespace {

simloop::Scenario pusht() {
  return simloop::Scenario::from_toml_file(std::string(SIMLOOP_TEST_SCENES) + "/pusht.toml");
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

struct Pair {
  explicit Pair(const simloop::Scenario& s)
      : scene(simloop::load_scene(s)), episodes(scene, s, simloop::ScenarioConfig{}, 1) {}
  simloop::Model scene;
  simloop::Episodes episodes;
  std::vector<double> row = std::vector<double>(static_cast<std::size_t>(episodes.width()));
  std::vector<double> step(double action) {
    std::vector<double> actions(static_cast<std::size_t>(episodes.nu()), action);
    std::uint8_t terminated = 0, truncated = 0;
    episodes.step(actions.data(), actions.size(), 10, nullptr, 0, row.data(), &terminated, &truncated);
    return row;
  }
};

}  // namespace

TEST(EpisodeStage, NothingWrittenGivesResetsBitsAndAWriteIsObserved) {
  const simloop::Scenario scenario = pusht();
  Pair plain(scenario), staged(scenario);
  for (std::uint64_t seed : {0u, 5u}) {
    plain.episodes.reset(0, seed, plain.row.data());
    staged.episodes.stage_reset(0, seed);
    staged.episodes.commit_reset(0, staged.row.data());
    EXPECT_TRUE(same_bits(plain.row, staged.row)) << "seed " << seed;
    for (int k = 0; k < 5; ++k) EXPECT_TRUE(same_bits(plain.step(0.3), staged.step(0.3))) << "seed " << seed;
  }
  staged.episodes.stage_reset(0, 1);
  const simloop::FieldView qpos = staged.episodes.staged_field(0, "qpos");
  double* q = static_cast<double*>(qpos.data);
  q[0] += 0.05;  // the T-block's x (its free joint's first coordinate)
  const double written = q[0];
  staged.episodes.commit_reset(0, staged.row.data());
  EXPECT_EQ(staged.episodes.data(0)->qpos[0], written);
  plain.episodes.reset(0, 1, plain.row.data());
  EXPECT_FALSE(same_bits(plain.row, staged.row));
}

TEST(EpisodeStage, AStageNeverCommittedChangesNothing) {
  const simloop::Scenario scenario = pusht();
  Pair plain(scenario), staged(scenario);
  plain.episodes.reset(0, 2, plain.row.data());
  staged.episodes.reset(0, 2, staged.row.data());
  plain.step(0.2), staged.step(0.2);
  staged.episodes.stage_reset(0, 9);
  static_cast<double*>(staged.episodes.staged_field(0, "qvel").data)[0] = 3.0;
  // (not committed: the hook failed) the episode goes on as it was
  for (int k = 0; k < 5; ++k) EXPECT_TRUE(same_bits(plain.step(0.2), staged.step(0.2)));
  EXPECT_EQ(plain.episodes.steps_taken(0), staged.episodes.steps_taken(0));
  staged.episodes.stage_reset(0, 9);  // and a later stage starts afresh, the write gone
  staged.episodes.commit_reset(0, staged.row.data());
  plain.episodes.reset(0, 9, plain.row.data());
  EXPECT_TRUE(same_bits(plain.row, staged.row));
  EXPECT_THROW(staged.episodes.commit_reset(0, staged.row.data()), simloop::InvalidArgument);  // committed once
  EXPECT_THROW(static_cast<void>(staged.episodes.staged_field(0, "qpos")), simloop::InvalidArgument);
}
