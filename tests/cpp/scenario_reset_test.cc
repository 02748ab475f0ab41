// How a run starts ([reset] in a scenario file, or one episode's reset):
// the state, noise on it and scene parameters, drawn from the run's seed
// after the disturbances, the same in a run, a batch and an episode.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "simloop/episode.hpp"
#include "simloop/errors.hpp"
#include "simloop/output.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/scene_params.hpp"
#include "test_util.hpp"

namespace {

using simloop::InvalidArgument;
using simloop::Scenario;

// PushT with a drawn disturbance and, after it, `reset` (a [reset] table's body).
Scenario pusht(const std::string& reset = "") {
  return Scenario::from_toml_string(
      "name = \"pusht-reset\"\nscene = \"pusht.xml\"\nsteps = 300\n"
      "[[control]]\nactuator = \"push_x\"\nvalue = 0.8\n"
      "[[disturbance]]\nbody = \"tblock\"\nnewtons = [0.5, 1.5]\n"
      "direction = [0, 1, 0]\nrandom_sign = true\nstart_step = 100\nsteps = 50\n"
      "[record]\nbodies = [\"tblock\"]\njoints = [\"slide_x\"]\n"
      "actuators = [\"push_x\", \"push_y\"]\n" +
          (reset.empty() ? "" : "[reset]\n" + reset),
      "pusht-reset", SIMLOOP_TEST_SCENES);
}

const simloop::Model& scene() {
  static const simloop::Model model = simloop::load_scene(pusht());
  return model;
}

simloop::RunRecord run(const Scenario& s, std::uint64_t seed, const simloop::Model& model = scene()) {
  simloop::ScenarioConfig config;
  config.seed = seed;
  return simloop::run_scenario(model, s, config);
}

double at(const simloop::RunRecord& r, std::int64_t row, const std::string& column) {
  for (std::size_t c = 0; c < r.columns.size(); ++c) {
    if (r.columns[c].name == column) return r.trajectory.at(row, static_cast<std::int64_t>(c));
  }
  ADD_FAILURE() << "no column " << column;
  return NAN;
}

bool same_bits(const simloop::RunRecord& a, const simloop::RunRecord& b) {
  const simloop::Trajectory& x = a.trajectory;
  const simloop::Trajectory& y = b.trajectory;
  return x.rows() == y.rows() && x.columns() == y.columns() &&
         std::memcmp(x.data(), y.data(), sizeof(double) * static_cast<size_t>(x.rows() * x.columns())) == 0;
}

using test::error_of;

TEST(ScenarioReset, AGivenStateIsWhereTheRunStarts) {
  // PushT: tblock's free joint (7), then slide_x and slide_y.
  const simloop::RunRecord r =
      run(pusht("qpos = [0.3, 0.1, 0.02, 0, 0, 0, 2, -0.05, 0.0]\nqvel = [0, 0.5, 0, 0, 0, 0, 0, 0]\n"), 0);
  EXPECT_EQ(at(r, 0, "tblock_x"), 0.3);
  EXPECT_EQ(at(r, 0, "tblock_y"), 0.1);
  EXPECT_EQ(at(r, 0, "tblock_vy"), 0.5);
  EXPECT_EQ(at(r, 0, "tblock_qw"), 0.0);  // renormalised: (0, 0, 0, 2) is (0, 0, 0, 1)
  EXPECT_EQ(at(r, 0, "tblock_qz"), 1.0);
  EXPECT_EQ(at(r, 0, "slide_x_pos"), -0.05);
}

TEST(ScenarioReset, NoiseIsDrawnFromTheSeedAfterTheDisturbances) {
  const Scenario noisy = pusht("qpos_noise = 0.01\nqvel_noise = 0.1\n");
  const simloop::RunRecord plain = run(pusht(), 7), a = run(noisy, 7), b = run(noisy, 7), c = run(noisy, 8);
  EXPECT_TRUE(same_bits(a, b));  // the seed decides
  EXPECT_NE(at(a, 0, "tblock_x"), at(c, 0, "tblock_x"));
  EXPECT_NE(at(a, 0, "tblock_x"), at(plain, 0, "tblock_x"));
  EXPECT_LE(std::abs(at(a, 0, "tblock_x") - 0.2), 0.01);
  // The disturbance is drawn first: the noise changes none of its draws.
  ASSERT_EQ(a.schedule.forces.size(), 1u);
  EXPECT_EQ(a.schedule.forces[0].wrench, plain.schedule.forces[0].wrench);
  const double qw = at(a, 0, "tblock_qw"), qx = at(a, 0, "tblock_qx"), qy = at(a, 0, "tblock_qy"),
               qz = at(a, 0, "tblock_qz");
  EXPECT_NEAR(qw * qw + qx * qx + qy * qy + qz * qz, 1.0, 1e-15);
}

TEST(ScenarioReset, ParamsAreTheRunsOwnSceneCopy) {
  // A [reset] param's value runs the very bits of a model with that
  // parameter (every geom's friction: MuJoCo takes the larger of two).
  const simloop::RunRecord drawn = run(pusht("[[reset.param]]\nkind = \"friction\"\nvalue = 0.3\n"), 3);
  const simloop::Model low_friction =
      simloop::with_scene_params(scene(), {{simloop::SceneParam::Kind::kFriction, "", 0.3}});
  EXPECT_TRUE(same_bits(drawn, run(pusht(), 3, low_friction)));
  EXPECT_FALSE(same_bits(drawn, run(pusht(), 3)));
  EXPECT_EQ(scene().get()->geom_friction[0], 1.0);  // the shared scene is untouched
  // Drawn per run, from the seed: uniform in [low, high].
  const Scenario ranged = pusht("[[reset.param]]\nkind = \"gravity\"\nuniform = [4.0, 12.0]\n");
  const simloop::RunRecord g1 = run(ranged, 1), g2 = run(ranged, 2);
  ASSERT_EQ(g1.schedule.start.params.size(), 1u);
  const double v1 = g1.schedule.start.params[0].value, v2 = g2.schedule.start.params[0].value;
  EXPECT_TRUE(v1 >= 4.0 && v1 < 12.0 && v2 >= 4.0 && v2 < 12.0 && v1 != v2);
  // What was drawn is reported, in metrics.json and the summary; a run that
  // draws none has no "params" key.
  const std::string metrics = simloop::metrics_json(g1);
  char value[32];
  std::snprintf(value, sizeof value, "%.6f", v1);
  EXPECT_NE(metrics.find("\"params\": [\n    {\n      \"kind\": \"gravity\",\n      \"name\": \"\",\n      "
                         "\"value\": " +
                         std::string(value)),
            std::string::npos)
      << metrics;
  std::snprintf(value, sizeof value, "%.4g", v1);
  EXPECT_NE(simloop::summary_text(g1).find("scene parameters drawn: gravity = " + std::string(value) + "\n"),
            std::string::npos)
      << simloop::summary_text(g1);
  EXPECT_EQ(simloop::metrics_json(run(pusht(), 1)).find("\"params\""), std::string::npos);
}

TEST(ScenarioReset, AModelValueIsDrawnReportedAndRun) {
  // Any writable mjModel value, by object and index: a geom's torsional
  // friction, every geom's alpha (a float array: drawn, then rounded to float).
  const Scenario s = pusht(
      "[[reset.param]]\nkind = \"model\"\nfield = \"actuator_gear\"\nname = \"push_x\"\nuniform = [2.0, 4.0]\n"
      "[[reset.param]]\nkind = \"model\"\nfield = \"geom_rgba\"\nindex = 3\nuniform = [0.2, 0.9]\n");
  const simloop::RunRecord r = run(s, 4);
  ASSERT_EQ(r.schedule.start.params.size(), 2u);
  const simloop::SceneParam gear = r.schedule.start.params[0], alpha = r.schedule.start.params[1];
  EXPECT_TRUE(gear.value >= 2.0 && gear.value < 4.0 && gear.field == "actuator_gear" && gear.index == 0);
  EXPECT_EQ(alpha.value, static_cast<double>(static_cast<float>(alpha.value)));
  EXPECT_TRUE(same_bits(r, run(pusht(), 4, simloop::with_scene_params(scene(), {gear, alpha}))));
  EXPECT_FALSE(same_bits(r, run(pusht(), 4)));
  const std::vector<std::pair<std::string, double>> columns = simloop::drawn_columns(r.schedule.start);
  ASSERT_EQ(columns.size(), 2u);
  EXPECT_EQ(columns[0], std::make_pair(std::string("actuator_gear_push_x_0"), gear.value));
  EXPECT_EQ(columns[1].first, "geom_rgba_3");
  const std::string metrics = simloop::metrics_json(r);
  EXPECT_NE(metrics.find("\"kind\": \"model\",\n      \"name\": \"push_x\","), std::string::npos) << metrics;
  EXPECT_NE(metrics.find("\"field\": \"actuator_gear\",\n      \"index\": 0"), std::string::npos) << metrics;
  char value[32];
  std::snprintf(value, sizeof value, "%.4g", gear.value);
  EXPECT_NE(simloop::summary_text(r).find("scene parameters drawn: actuator_gear[0] of 'push_x' = " +
                                          std::string(value) + ", geom_rgba[3] of every row = "),
            std::string::npos)
      << simloop::summary_text(r);
  const auto run_error = [](const std::string& reset) { return error_of([&] { (void)run(pusht(reset), 0); }); };
  EXPECT_EQ(
      run_error("[[reset.param]]\nkind = \"model\"\nfield = \"geom_size\"\nname = \"t_bar\"\nvalue = 1\n")
          .rfind("reset.param[0]: geom_size[0] of 't_bar' = 1.0: mjModel's geom_size is not one a run may vary", 0),
      0u);
}

TEST(ScenarioReset, ABatchAndAnEpisodeStartAsARunDoes) {
  const Scenario s =
      pusht("qpos_noise = 0.02\n[[reset.param]]\nkind = \"mass\"\nname = \"tblock\"\nuniform = [0.2, 0.6]\n");
  std::vector<simloop::ScenarioConfig> configs(4);
  for (std::size_t i = 0; i < configs.size(); ++i) configs[i].seed = 10 + i;
  for (const int threads : {1, 2}) {
    const std::vector<simloop::RunRecord> batch = simloop::run_scenario_batch(scene(), s, configs, threads);
    for (std::size_t i = 0; i < configs.size(); ++i)
      EXPECT_TRUE(same_bits(batch[i], run(s, 10 + i))) << i << " " << threads;
  }
  // An episode's first observation is the run's row 0 (after step and time).
  simloop::Episodes episodes(scene(), pusht(), simloop::ScenarioConfig{}, 1);
  std::vector<double> obs(static_cast<std::size_t>(episodes.width()));
  episodes.reset(0, 12, obs.data(), &s.reset);
  const simloop::RunRecord r = run(s, 12);
  for (std::size_t c = 2; c < obs.size(); ++c) {
    if (r.columns[c].name.find("ctrl") != std::string::npos || r.columns[c].name.find("force") != std::string::npos) {
      continue;  // the actions' inputs, not the scenario's
    }
    EXPECT_EQ(obs[c], r.trajectory.at(0, static_cast<std::int64_t>(c))) << r.columns[c].name;
  }
  EXPECT_NE(episodes.model(0).get(), scene().get());  // its own copy, with the drawn mass
  EXPECT_EQ(episodes.model(0).get()->body_mass[1], r.schedule.start.params[0].value);
}

TEST(ScenarioReset, BadResetsNameTheKey) {
  const auto file_error = [](const std::string& reset) { return error_of([&] { (void)pusht(reset); }); };
  EXPECT_EQ(file_error("qpos_nosie = 1\n"),
            "pusht-reset: reset.qpos_nosie: unknown key (did you mean 'qpos_noise'?); known keys: qpos, qvel, "
            "qpos_noise, qvel_noise, qpos_noise_distribution, qvel_noise_distribution, keyframe, goal, param");
  EXPECT_EQ(file_error("qvel_noise = -1\n"),
            "pusht-reset: reset.qvel_noise: must not be negative (a uniform noise's half-width or a normal noise's "
            "standard deviation), got -1.0");
  // A noise or range so wide that its draw would overflow to inf (and the state to nan).
  EXPECT_EQ(file_error("qpos_noise = 1e308\n"),
            "pusht-reset: reset.qpos_noise: is too large: [-x, x] must be a range a double holds, got 1e+308");
  EXPECT_EQ(file_error("[[reset.param]]\nkind = \"mass\"\nname = \"tblock\"\nuniform = [-1e308, 1e308]\n"),
            "pusht-reset: reset.param[0].uniform: is too wide: high - low must be a number a double holds");
  EXPECT_EQ(file_error("[[reset.param]]\nkind = \"stiffness\"\nvalue = 1\n"),
            "pusht-reset: reset.param[0].kind: scene parameter kind must be one of 'friction', 'mass', 'damping', "
            "'gravity', 'model', got 'stiffness'");
  EXPECT_EQ(file_error("[[reset.param]]\nkind = \"model\"\nname = \"t_bar\"\nvalue = 1\n"),
            "pusht-reset: reset.param[0].field: missing: a model value names an mjModel array (geom_friction)");
  EXPECT_EQ(file_error("[[reset.param]]\nkind = \"mass\"\nname = \"tblock\"\nindex = 1\nvalue = 1\n"),
            "pusht-reset: reset.param[0].index: belongs to kind = \"model\" only");
  EXPECT_EQ(file_error("[[reset.param]]\nkind = \"model\"\nfield = \"geom_rgba\"\nindex = -1\nvalue = 1\n"),
            "pusht-reset: reset.param[0].index: must be at least 0, got -1");
  EXPECT_EQ(file_error("[[reset.param]]\nkind = \"friction\"\nvalue = 1\nuniform = [0, 1]\n"),
            "pusht-reset: reset.param[0]: give value (fixed) or uniform = [low, high] (drawn per run)");
  const auto run_error = [](const std::string& reset) { return error_of([&] { (void)run(pusht(reset), 0); }); };
  EXPECT_EQ(run_error("qpos = [1, 2, 3]\n"), "reset.qpos must hold the scene's nq = 9 values, got 3");
  EXPECT_EQ(run_error("[[reset.param]]\nkind = \"friction\"\nname = \"flor\"\nvalue = 0.5\n"),
            "reset.param[0]: friction of 'flor' = 0.5: no geom named 'flor' (did you mean 'floor'?); the scene's "
            "geoms: floor, "
            "goal, t_bar, t_stem, tip");
  EXPECT_EQ(run_error("[[reset.param]]\nkind = \"gravity\"\nname = \"floor\"\nvalue = 9\n"),
            "reset.param[0]: gravity of 'floor' = 9.0: gravity is the whole scene's: give no name");
  // An episode's own reset: refused before it changes anything.
  simloop::Episodes episodes(scene(), pusht(), simloop::ScenarioConfig{}, 1);
  std::vector<double> obs(static_cast<std::size_t>(episodes.width())), again(obs.size());
  episodes.reset(0, 1, obs.data());
  simloop::ResetSpec bad;
  bad.qvel = {1.0};
  EXPECT_EQ(error_of([&] { episodes.reset(0, 2, again.data(), &bad); }),
            "reset.qvel must hold the scene's nv = 8 values, got 1");
  EXPECT_EQ(episodes.steps_taken(0), 0);
}

TEST(ScenarioReset, OptionsOverTheScenariosResetReplaceOnlyTheKeysTheyName) {
  const Scenario own = Scenario::from_toml_string(
      "[reset]\nqpos = [1, 2]\nqpos_noise = 0.1\n[[reset.param]]\nkind = 'gravity'\nvalue = 5.0\n", "own");
  const simloop::ResetSpec noise = simloop::reset_over(own.reset, "[reset]\nqvel_noise = 0.5\n", "options");
  EXPECT_EQ(noise.qpos, own.reset.qpos);
  EXPECT_EQ(noise.qpos_noise.scale, 0.1);
  EXPECT_EQ(noise.qvel_noise.scale, 0.5);
  ASSERT_EQ(noise.params.size(), 1U);
  EXPECT_EQ(noise.params[0].low, 5.0);
  const simloop::ResetSpec none = simloop::reset_over(own.reset, "[reset]\nparam = []\nqpos_noise = 0.0\n", "options");
  EXPECT_TRUE(none.params.empty());
  EXPECT_EQ(none.qpos_noise.scale, 0.0);
  EXPECT_EQ(none.qpos, own.reset.qpos);
  const simloop::ResetSpec mass =
      simloop::reset_over(own.reset, "[[reset.param]]\nkind = 'mass'\nname = 'box'\nvalue = 2.0\n", "options");
  ASSERT_EQ(mass.params.size(), 1U);
  EXPECT_EQ(mass.params[0].name, "box");
  EXPECT_EQ(mass.qpos_noise.scale, 0.1);
  EXPECT_EQ(error_of([&] { (void)simloop::reset_over(own.reset, "[reset]\nqpos_noise = -1\n", "options"); }),
            "options: reset.qpos_noise: must not be negative (a uniform noise's half-width or a normal noise's "
            "standard deviation), got -1.0");
}

}  // namespace
