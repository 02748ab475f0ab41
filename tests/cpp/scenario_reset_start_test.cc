// Starts a trainer shapes: a keyframe by name, then the other [reset] keys
// over it, and goals (a mocap body's position) drawn per run.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "simloop/episode.hpp"
#include "simloop/errors.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"
#include "test_util.hpp"

namespace {

using simloop::Scenario;
using test::error_of;

// An arm's two hinges (with a position actuator each), a mocap target, and
// two keyframes: "home" (a pose, a speed, a ctrl, the target somewhere) and "up".
constexpr const char* kReach = R"(<mujoco>
  <worldbody>
    <body name="arm"><joint name="shoulder" type="hinge" axis="0 0 1"/><geom type="capsule" size="0.05" fromto="0 0 0 0.3 0 0"/>
      <body name="forearm" pos="0.3 0 0"><joint name="elbow" type="hinge" axis="0 0 1"/>
        <geom type="capsule" size="0.04" fromto="0 0 0 0.3 0 0"/></body></body>
    <body name="target" mocap="true" pos="0.5 0 0"><geom size="0.02" contype="0" conaffinity="0"/></body>
  </worldbody>
  <actuator><position name="reach" joint="shoulder" kp="5"/></actuator>
  <keyframe>
    <key name="home" qpos="0.4 -0.8" qvel="0.1 0.2" ctrl="0.3" mpos="0.1 0.2 0.3" mquat="1 0 0 0"/>
    <key name="up" qpos="1.5 0"/>
  </keyframe>
</mujoco>)";

struct Reach {
  test::TempDir dir;
  Reach() { test::write_text(dir.path() / "reach.xml", kReach); }
  [[nodiscard]] Scenario scenario(const std::string& reset) const {
    return Scenario::from_toml_string(
        "scene = \"reach.xml\"\nsteps = 5\n[record]\njoints = [\"shoulder\", \"elbow\"]\nbodies = [\"target\"]\n"
        "actuators = [\"reach\"]\n[reset]\n" +
            reset,
        "reach", dir.path());
  }
};

const Reach& reach() {
  static const Reach r;
  return r;
}

simloop::RunRecord run(const std::string& reset, std::uint64_t seed) {
  const Scenario s = reach().scenario(reset);
  simloop::ScenarioConfig config;
  config.seed = seed;
  return simloop::run_scenario(simloop::load_scene(s), s, config);
}

double at(const simloop::RunRecord& r, const std::string& column) {
  for (std::size_t c = 0; c < r.columns.size(); ++c) {
    if (r.columns[c].name == column) return r.trajectory.at(0, static_cast<std::int64_t>(c));
  }
  ADD_FAILURE() << "no column " << column;
  return 0.0;
}

TEST(ResetStart, AKeyframeIsWhereTheRunStartsAndTheOtherKeysApplyOverIt) {
  const simloop::RunRecord home = run("keyframe = \"home\"\n", 0);
  EXPECT_EQ(at(home, "shoulder_pos"), 0.4);
  EXPECT_EQ(at(home, "elbow_pos"), -0.8);
  EXPECT_EQ(at(home, "elbow_vel"), 0.2);
  EXPECT_EQ(at(home, "target_y"), 0.2);  // the keyframe's mocap_pos too
  const simloop::RunRecord plain = run("", 0);
  EXPECT_EQ(at(plain, "shoulder_pos"), 0.0);
  EXPECT_EQ(at(plain, "target_x"), 0.5);
  // Over it: a given qvel replaces the keyframe's; noise is about the keyframe's pose.
  const simloop::RunRecord over = run("keyframe = \"home\"\nqvel = [0, 0]\nqpos_noise = {elbow = 0.01}\n", 3);
  EXPECT_EQ(at(over, "shoulder_pos"), 0.4);
  EXPECT_NE(at(over, "elbow_pos"), -0.8);
  EXPECT_LE(std::abs(at(over, "elbow_pos") + 0.8), 0.01);
  EXPECT_EQ(at(over, "elbow_vel"), 0.0);
  EXPECT_EQ(at(run("keyframe = \"up\"\n", 0), "shoulder_pos"), 1.5);
  // Reset options name it as a file does; "" is the scene's own pose again.
  const Scenario own = reach().scenario("keyframe = \"home\"\n");
  EXPECT_EQ(simloop::reset_over(own.reset, "[reset]\nqvel = [0, 0]\n", "options").keyframe, "home");
  EXPECT_EQ(simloop::reset_over(own.reset, "[reset]\nkeyframe = \"\"\n", "options").keyframe, "");
}

TEST(ResetStart, AGoalIsWhereTheStateSaysPerSeed) {
  const std::string goal = "[[reset.goal]]\nbody = \"target\"\nuniform = [[0.2, -0.3, 0.0], [0.6, 0.3, 0.0]]\n";
  const simloop::RunRecord a = run(goal, 1), again = run(goal, 1), b = run(goal, 2);
  ASSERT_EQ(a.schedule.start.goals.size(), 1U);
  const std::array<double, 3> drawn = a.schedule.start.goals[0].pos;
  EXPECT_EQ(at(a, "target_x"), drawn[0]);  // the state holds what was drawn
  EXPECT_EQ(at(a, "target_y"), drawn[1]);
  EXPECT_EQ(at(a, "target_z"), 0.0);  // [0, 0]: exactly 0
  EXPECT_TRUE(drawn[0] >= 0.2 && drawn[0] < 0.6 && drawn[1] >= -0.3 && drawn[1] < 0.3);
  EXPECT_EQ(again.schedule.start.goals[0].pos, drawn);
  EXPECT_NE(b.schedule.start.goals[0].pos, drawn);
  // After the keyframe's mocap_pos, and fixed with pos.
  const simloop::RunRecord fixed = run("keyframe = \"home\"\n[[reset.goal]]\nbody = \"target\"\npos = [1, 2, 3]\n", 0);
  EXPECT_EQ(at(fixed, "target_y"), 2.0);
  EXPECT_EQ(at(fixed, "shoulder_pos"), 0.4);
  // An episode's reset draws it from its seed alike.
  const Scenario s = reach().scenario(goal);
  const simloop::Model model = simloop::load_scene(s);
  simloop::Episodes episodes(model, s, simloop::ScenarioConfig{}, 1);
  std::vector<double> obs(static_cast<std::size_t>(episodes.width()));
  episodes.reset(0, 1, obs.data());
  EXPECT_EQ(episodes.data(0)->mocap_pos[0], drawn[0]);
}

TEST(ResetStart, UnknownKeyframesAndGoalsAreOneLineNamingTheKey) {
  const auto run_error = [](const std::string& reset) { return error_of([&] { (void)run(reset, 0); }); };
  EXPECT_EQ(run_error("keyframe = \"hoem\"\n"),
            "reset.keyframe: no keyframe named 'hoem' (did you mean 'home'?); the scene's keyframes: home, up");
  EXPECT_EQ(run_error("[[reset.goal]]\nbody = \"arm\"\npos = [0, 0, 0]\n"),
            "reset.goal[0].body: 'arm' is not a mocap body; the scene's mocap bodies: target");
  EXPECT_EQ(error_of([&] { (void)reach().scenario("[[reset.goal]]\nbody = \"target\"\nuniform = [[0, 0, 0]]\n"); }),
            "reach: reset.goal[0].uniform: expected 2 arrays of 3 numbers");
  EXPECT_EQ(error_of([&] { (void)reach().scenario("[[reset.goal]]\nbody = \"target\"\n"); }),
            "reach: reset.goal[0]: give pos = [x, y, z] (fixed) or uniform = [[x, y, z], [x, y, z]] (drawn per run: "
            "low, high)");
}

}  // namespace
