// Sim: the chapter's loop written with it, step by step, on the chapter's
// scene (its box and pusher found through the layout); and Sim on any scene:
// names, arrays, inputs, forces, state, keyframes, copies, and a model saved
// as bytes and loaded back.
#include "simloop/sim.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/run.hpp"
#include "simloop/state.hpp"
#include "test_util.hpp"

namespace {

using simloop::ChapterColumns;
using simloop::Model;
using simloop::Sim;
using simloop::Trajectory;

// The chapter's scene, loaded once.
const simloop::Model& scene() {
  static const simloop::Model model = simloop::pusher_scene();
  return model;
}

Model scene(const std::string& file) { return Model::from_file(std::string(SIMLOOP_TEST_SCENES) + "/" + file); }

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// Every actuator at a different ctrl, then n steps.
void drive(Sim& sim, int n) {
  std::vector<double> ctrl(static_cast<std::size_t>(sim.model().get()->nu));
  for (std::size_t i = 0; i < ctrl.size(); ++i) ctrl[i] = 0.6 - 0.25 * static_cast<double>(i);
  sim.set_ctrl(ctrl.data(), ctrl.size());
  sim.step(n);
}

// Sim's rhythm, written out as the chapter's loop, is the chapter's loop.
TEST(Sim, TheChaptersLoopWrittenWithSimMatchesRun) {
  simloop::RunConfig config;
  config.steps = 600;
  const auto reference = simloop::run(scene(), config);
  simloop::Sim sim(scene());
  const simloop::ChapterLayout at = simloop::chapter_layout(scene());
  const simloop::Shove& shove = reference.shove;
  const std::array<double, 3> push{0.0, shove.force_y(), 0.0}, none{};
  for (std::int64_t step = 0; step < config.steps; ++step) {
    sim.set_ctrl(1.0);
    if (step == shove.start_step) sim.apply_wrench(at.box_body, &push, nullptr);
    if (step == shove.start_step + shove.num_steps) sim.apply_wrench(at.box_body, &none, nullptr);
    sim.step();
  }
  const std::int64_t last = reference.trajectory.rows() - 1;
  const std::vector<double> pos = sim.read("qpos", at.box_qposadr, 3);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(pos[i], reference.trajectory.at(last, ChapterColumns::kBoxX + i));
  EXPECT_EQ(sim.data()->qpos[at.pusher_qposadr], reference.trajectory.at(last, ChapterColumns::kPusherX));
  EXPECT_EQ(sim.time(), reference.sim_time);
  EXPECT_EQ(sim.steps_taken(), 600);
}

TEST(Sim, AnAppliedForcePersistsUntilCleared) {
  simloop::Sim sim(scene());
  const simloop::ChapterLayout at = simloop::chapter_layout(scene());
  const double* applied = sim.data()->xfrc_applied + 6 * at.box_body;
  const double* velocity = sim.data()->qvel + at.box_dofadr;
  const std::array<double, 3> push{0.0, 9.0, 0.0};
  sim.apply_wrench(at.box_body, &push, nullptr);
  sim.step(10);
  EXPECT_EQ(applied[1], 9.0);  // MuJoCo did not clear it
  const double vy_after_10 = velocity[1];
  sim.step(10);
  EXPECT_GT(velocity[1], vy_after_10);  // still pushing: still accelerating
  sim.clear_forces();
  EXPECT_EQ(applied[1], 0.0);
  sim.step(200);
  EXPECT_NEAR(velocity[1], 0.0, 1e-3);  // friction stops it once the force is gone
}

TEST(Sim, ReadsContactsAndResets) {
  simloop::Sim sim(scene());
  const auto contacts = sim.contacts();
  ASSERT_FALSE(contacts.empty());
  for (const auto& c : contacts) {
    EXPECT_EQ(c.geom1, "floor");
    EXPECT_TRUE(c.geom2 == "box_geom" || c.geom2 == "pusher_geom") << c.geom2;
  }
  sim.set_ctrl(1.0);
  sim.set_timestep(0.01);
  sim.step(5);
  EXPECT_NEAR(sim.time(), 0.05, 1e-12);
  sim.reset();
  EXPECT_EQ(sim.time(), 0.0);
  EXPECT_EQ(sim.ctrl(), 0.0);
  EXPECT_EQ(sim.read("qpos", simloop::chapter_layout(scene()).box_qposadr, 1)[0], 0.4);
  EXPECT_EQ(sim.timestep(), 0.01);  // the timestep is the model's, kept across reset
  EXPECT_THROW(sim.step(0), simloop::InvalidArgument);
  EXPECT_THROW(sim.set_ctrl(NAN), simloop::InvalidArgument);
  EXPECT_THROW(sim.set_timestep(0.0), simloop::InvalidArgument);
}

TEST(PusherTrack, SlidesAlongXFromItsRestPose) {
  const simloop::PusherTrack track = simloop::pusher_track(scene());
  EXPECT_EQ(track.rest_position, (std::array<double, 3>{0.0, 0.0, 0.05}));
  EXPECT_EQ(track.axis, (std::array<double, 3>{1.0, 0.0, 0.0}));
  EXPECT_EQ(track.q0, 0.0);
}

TEST(SimAny, RunsASceneWithoutTheChaptersLayout) {
  const Model walker = scene("walker.xml");
  Sim sim(walker);
  drive(sim, 50);
  EXPECT_EQ(sim.steps_taken(), 50);
  EXPECT_NE(sim.data()->qpos[2], walker.get()->qpos0[2]);  // the walker moved
}

TEST(SimAny, NamedArraysAreMjDatasOwnAndReadsStayInside) {
  Sim sim(scene("walker.xml"));
  drive(sim, 20);
  const mjModel* m = sim.model().get();
  const simloop::ArrayView qpos = sim.array("qpos");
  EXPECT_EQ(qpos.data, sim.data()->qpos);
  EXPECT_EQ(qpos.rows, m->nq);
  EXPECT_EQ(qpos.width, 0);
  EXPECT_TRUE(qpos.writable);
  const simloop::ArrayView xquat = sim.array("xquat");
  EXPECT_EQ(xquat.rows, m->nbody);
  EXPECT_EQ(xquat.width, 4);
  EXPECT_FALSE(xquat.writable);
  EXPECT_EQ(test::error_of([&] { (void)sim.array("qacc"); }), "no Sim array named 'qacc'");
  EXPECT_EQ(sim.read("xquat", 4, 4), std::vector<double>(sim.data()->xquat + 4, sim.data()->xquat + 8));
  EXPECT_EQ(sim.read("qvel", m->nv, 0), std::vector<double>());
  EXPECT_EQ(test::error_of([&] { (void)sim.read("qvel", m->nv - 1, 2); }),
            "qvel has " + std::to_string(m->nv) + " values: cannot read 2 from index " + std::to_string(m->nv - 1));
  EXPECT_NE(test::error_of([&] { (void)sim.read("qvel", -1, 1); }), test::kNoInvalidArgument);
}

TEST(SimAny, UnknownNamesListWhatTheSceneHasWithALikelyFix) {
  Sim sim(scene("walker.xml"));
  EXPECT_EQ(sim.id(mjOBJ_BODY, "torso"), 1);
  EXPECT_EQ(test::error_of([&] { (void)sim.id(mjOBJ_BODY, "torsoo"); }),
            "no body named 'torsoo' (did you mean 'torso'?); the scene's bodies: world, torso, thigh_left, "
            "shin_left, thigh_right, shin_right");
  EXPECT_EQ(test::error_of([&] { (void)sim.id(mjOBJ_KEY, "stand"); }),
            "no keyframe named 'stand'; the scene has no keyframes");
  EXPECT_NE(test::error_of([&] {
              (void)sim.checked_index(mjOBJ_ACTUATOR, 4);
            }).find("actuator index 4 is out of range: the scene has 4 actuators (0 to 3)"),
            std::string::npos);
}

TEST(SimAny, CtrlVectorNeedsOneFiniteValuePerActuator) {
  Sim sim(scene("pusht.xml"));
  const std::array<double, 3> three{0.1, 0.2, 0.3};
  EXPECT_EQ(test::error_of([&] { sim.set_ctrl(three.data(), 3); }),
            "ctrl must have nu = 2 values (one per actuator), got 3");
  const std::array<double, 2> bad{0.1, std::nan("")};
  EXPECT_EQ(test::error_of([&] { sim.set_ctrl(bad.data(), 2); }), "ctrl[1] must be finite, got nan");
  EXPECT_EQ(sim.data()->ctrl[0], 0.0);  // nothing written
}

TEST(SimAny, AWrenchOnAnyBodyPersistsUntilCleared) {
  Sim sim(scene("pusht.xml"));
  const int block = sim.id(mjOBJ_BODY, "tblock");
  const std::array<double, 3> torque{0.0, 0.0, 0.05};
  sim.apply_wrench(block, nullptr, &torque);
  const double* slot = sim.data()->xfrc_applied + 6 * block;
  sim.step(100);
  EXPECT_EQ(slot[5], 0.05);
  EXPECT_EQ(slot[0], 0.0);                    // the force part, not given, left alone
  const double turned = sim.data()->qvel[5];  // the free joint's angular z
  EXPECT_GT(turned, 0.0);
  const std::array<double, 3> nan_force{std::nan(""), 0.0, 0.0};
  EXPECT_NE(test::error_of([&] { sim.apply_wrench(block, &nan_force, nullptr); }), test::kNoInvalidArgument);
  EXPECT_NE(test::error_of([&] { sim.apply_wrench(99, &nan_force, nullptr); }).find("body index 99 is out of range"),
            std::string::npos);
  sim.clear_forces();
  for (int i = 0; i < 6 * sim.model().get()->nbody; ++i) EXPECT_EQ(sim.data()->xfrc_applied[i], 0.0);
}

TEST(SimAny, AStateRestoredIntoAnotherSimGoesOnBitForBit) {
  for (const char* file : {"pusht.xml", "walker.xml"}) {
    const Model model = scene(file);
    Sim a(model);
    drive(a, 137);
    const std::vector<double> saved = a.state();
    drive(a, 200);
    Sim b(model);
    b.set_state(saved.data(), saved.size());
    drive(b, 200);
    EXPECT_TRUE(same_bits(a.state(), b.state())) << file;
    // MuJoCo's own state (mj_getState's, where MuJoCo has one): its first values, every tree awake.
    if (const std::size_t mujocos = simloop::mujoco_state_size(model.get()); mujocos > 0) {
      Sim c(model);
      c.set_state(saved.data(), mujocos);
      drive(c, 200);
      EXPECT_TRUE(same_bits(a.state(), c.state())) << file;
      const std::vector<double> state = c.state();
      EXPECT_TRUE(same_bits(c.mujoco_state(), std::vector<double>(state.begin(), state.begin() + mujocos))) << file;
    } else {
      EXPECT_NE(test::error_of([&] { (void)b.mujoco_state(); }).find("needs MuJoCo 3.3 or later"), std::string::npos);
    }
    EXPECT_NE(test::error_of([&] {
                b.set_state(saved.data(), saved.size() + 1);
              }).find("state must have " + std::to_string(saved.size()) + " values"),
              std::string::npos);
  }
}

TEST(SimAny, ACopyIsIndependentAndStepsAsTheOriginalWould) {
  Sim original(scene("pusht.xml"));
  drive(original, 80);
  Sim copy(original);
  EXPECT_NE(copy.data(), original.data());
  drive(copy, 40);
  EXPECT_EQ(original.steps_taken(), 80);  // stepping the copy did not move the original
  EXPECT_EQ(copy.steps_taken(), 120);
  drive(original, 40);
  EXPECT_TRUE(same_bits(original.state(), copy.state()));
}

TEST(SimAny, ACopyKeepsItsWarningsWhenTheOriginalIsGone) {
  auto original = std::make_unique<Sim>(scene().with_timestep(1.0));  // the box goes through the floor
  original->set_ctrl(1.0);
  original->step(200);
  const std::vector<simloop::Warning> warned = original->warnings();
  ASSERT_FALSE(warned.empty());
  ASSERT_EQ(warned.back().name, "simloop_DIVERGED");
  const Sim copy(*original);
  original.reset();
  const std::vector<std::vector<char>> reuse(64, std::vector<char>(56, 'x'));  // the freed memory, taken again
  const std::vector<simloop::Warning> kept = copy.warnings();
  ASSERT_EQ(kept.size(), warned.size());
  EXPECT_EQ(kept.back().message, warned.back().message);
  EXPECT_EQ(kept.back().count, warned.back().count);
}

TEST(SimAny, ResetsToAKeyframe) {
  const Model model = Model::from_xml_string(R"(<mujoco model="keyed">
  <worldbody><body name="ball" pos="0 0 1"><freejoint/><geom size="0.1" mass="1"/></body></worldbody>
  <keyframe><key name="high" qpos="0 0 3 1 0 0 0"/></keyframe>
</mujoco>)");
  Sim sim(model);
  sim.step(10);
  sim.reset_to_keyframe(sim.id(mjOBJ_KEY, "high"));
  EXPECT_EQ(sim.data()->qpos[2], 3.0);
  EXPECT_EQ(sim.time(), 0.0);
  EXPECT_EQ(sim.steps_taken(), 0);
  EXPECT_NE(test::error_of([&] {
              sim.reset_to_keyframe(1);
            }).find("keyframe index 1 is out of range: the scene has 1 keyframe (0 to 0); the scene's keyframes: high"),
            std::string::npos);
}

TEST(SimAny, AModelSavedAsBytesLoadsBackAndStepsToTheSameBits) {
  for (const char* file : {"pusht.xml", "walker.xml"}) {
    const Model model = scene(file).with_timestep(0.003);
    const std::string bytes = model.to_bytes();
    const Model loaded = Model::from_bytes(bytes);
    EXPECT_EQ(loaded.to_bytes(), bytes) << file;
    EXPECT_EQ(loaded.timestep(), 0.003);
    EXPECT_EQ(loaded.name(), model.name());
    Sim a(model), b(loaded);
    drive(a, 300);
    drive(b, 300);
    EXPECT_TRUE(same_bits(a.state(), b.state())) << file;
  }
  EXPECT_THROW((void)Model::from_bytes("not a model"), simloop::InvalidArgument);
  EXPECT_THROW((void)Model::from_bytes(""), simloop::InvalidArgument);
}

TEST(SimAny, EveryOneByteDamageToASavedModelIsRefusedBeforeMuJoCoReadsIt) {
  const std::string bytes = scene("walker.xml").to_bytes();
  for (std::size_t at = 0; at < bytes.size(); at += 1 + bytes.size() / 1500) {
    std::string damaged = bytes;
    damaged[at] = static_cast<char>(damaged[at] ^ (1 + at % 255));
    const std::string message = test::error_of([&] { (void)Model::from_bytes(damaged); });
    EXPECT_TRUE(message.find("the saved model is damaged") != std::string::npos ||
                message.find("not a model simloop saved") != std::string::npos)
        << "byte " << at << ": " << message;
  }
  std::string cut = bytes.substr(0, bytes.size() / 2);
  EXPECT_NE(test::error_of([&] { (void)Model::from_bytes(cut); }), "");
}

}  // namespace
