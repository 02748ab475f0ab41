// Scene parameters applied to a copy of the model: the copy changes what a
// run does, the original does not change, and the scene's own value changes
// nothing at all (bit for bit).
#include "simloop/scene_params.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/run.hpp"

namespace {

using Kind = simloop::SceneParam::Kind;

simloop::RunResult run_on(const simloop::Model& model) {
  simloop::RunConfig config;  // the chapter's run, seed 0
  config.steps = 600;
  return simloop::run(model, config);
}

bool same_bits(const simloop::RunResult& a, const simloop::RunResult& b) {
  const simloop::Trajectory& x = a.trajectory;
  const simloop::Trajectory& y = b.trajectory;
  return x.rows() == y.rows() && x.columns() == y.columns() &&
         std::memcmp(x.data(), y.data(),
                     sizeof(double) * static_cast<size_t>(x.rows()) * static_cast<size_t>(x.columns())) == 0;
}

std::string error_of(const simloop::Model& model, const std::vector<simloop::SceneParam>& params) {
  try {
    (void)simloop::with_scene_params(model, params);
  } catch (const simloop::InvalidArgument& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SceneParams, TheScenesOwnValuesChangeNoBit) {
  const simloop::Model scene = simloop::pusher_scene();
  const simloop::RunResult original = run_on(scene);
  // The chapter's geoms all have MuJoCo's default friction 1, the box weighs
  // 0.5 kg, the pusher's slide has damping 4.
  for (const std::vector<simloop::SceneParam>& params : std::vector<std::vector<simloop::SceneParam>>{
           {{Kind::kFriction, "", 1.0}},
           {{Kind::kFriction, "box_geom", 1.0}},
           {{Kind::kMass, "box", 0.5}},
           {{Kind::kMass, "pusher", 1.0}},
           {{Kind::kDamping, "pusher_slide", 4.0}},
           {{Kind::kMass, "box", 0.5}, {Kind::kFriction, "", 1.0}, {Kind::kDamping, "pusher_slide", 4.0}}}) {
    const simloop::Model copy = simloop::with_scene_params(scene, params);
    EXPECT_NE(copy.get(), scene.get());
    EXPECT_EQ(std::memcmp(copy.get()->body_invweight0, scene.get()->body_invweight0,
                          sizeof(double) * 2 * static_cast<size_t>(scene.get()->nbody)),
              0);
    EXPECT_TRUE(same_bits(run_on(copy), original)) << params.front().name;
  }
}

TEST(SceneParams, OtherValuesChangeTheRunAndLeaveTheOriginalAlone) {
  const simloop::Model scene = simloop::pusher_scene();
  const double box_x = run_on(scene).trajectory.at(600, simloop::ChapterColumns::kBoxX);
  for (const simloop::SceneParam& p : std::vector<simloop::SceneParam>{
           {Kind::kFriction, "", 0.3}, {Kind::kMass, "box", 2.0}, {Kind::kDamping, "pusher_slide", 20.0}}) {
    const simloop::Model copy = simloop::with_scene_params(scene, {p});
    EXPECT_NE(run_on(copy).trajectory.at(600, simloop::ChapterColumns::kBoxX), box_x)
        << simloop::scene_param_kind_name(p.kind);
  }
  EXPECT_EQ(run_on(scene).trajectory.at(600, simloop::ChapterColumns::kBoxX), box_x);
  EXPECT_EQ(scene.get()->body_mass[1], 0.5);
  EXPECT_EQ(scene.get()->geom_friction[0], 1.0);
}

TEST(SceneParams, WhatEachParamWrites) {
  const simloop::Model scene = simloop::pusher_scene();
  const mjModel* s = scene.get();
  const int box = mj_name2id(s, mjOBJ_BODY, "box");
  const int box_geom = mj_name2id(s, mjOBJ_GEOM, "box_geom");
  const int slide = mj_name2id(s, mjOBJ_JOINT, "pusher_slide");

  const simloop::Model heavier = simloop::with_scene_params(scene, {{Kind::kMass, "box", 2.0}});
  const mjModel* h = heavier.get();
  EXPECT_EQ(h->body_mass[box], 2.0);
  for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(h->body_inertia[3 * box + k], 4.0 * s->body_inertia[3 * box + k]);
  EXPECT_DOUBLE_EQ(h->body_subtreemass[0], s->body_subtreemass[0] + 1.5);
  EXPECT_LT(h->body_invweight0[2 * box], s->body_invweight0[2 * box]);  // mj_setConst ran: heavier, less mobile

  const simloop::Model slick = simloop::with_scene_params(scene, {{Kind::kFriction, "box_geom", 0.2}});
  for (int g = 0; g < s->ngeom; ++g) {
    EXPECT_EQ(slick.get()->geom_friction[3 * g], g == box_geom ? 0.2 : s->geom_friction[3 * g]);
    EXPECT_EQ(slick.get()->geom_friction[3 * g + 1], s->geom_friction[3 * g + 1]);  // torsional, rolling kept
  }
  const simloop::Model all_slick = simloop::with_scene_params(scene, {{Kind::kFriction, "", 0.2}});
  for (int g = 0; g < s->ngeom; ++g) EXPECT_EQ(all_slick.get()->geom_friction[3 * g], 0.2);

  const simloop::Model damped = simloop::with_scene_params(scene, {{Kind::kDamping, "", 7.0}});
  for (int v = 0; v < s->nv; ++v) EXPECT_EQ(damped.get()->dof_damping[v], 7.0);  // the box's free joint's 6 too
  const simloop::Model one = simloop::with_scene_params(scene, {{Kind::kDamping, "pusher_slide", 7.0}});
  for (int v = 0; v < s->nv; ++v) EXPECT_EQ(one.get()->dof_damping[v], s->dof_jntid[v] == slide ? 7.0 : 0.0);
  // A later param on the same thing wins.
  const simloop::Model twice =
      simloop::with_scene_params(scene, {{Kind::kFriction, "", 0.2}, {Kind::kFriction, "box_geom", 0.7}});
  EXPECT_EQ(twice.get()->geom_friction[3 * box_geom], 0.7);
}

TEST(SceneParams, BadNamesAndValuesAreRefusedByName) {
  const simloop::Model scene = simloop::pusher_scene();
  EXPECT_EQ(error_of(scene, {{Kind::kMass, "bx", 1.0}}),
            "mass of 'bx' = 1.0: no body named 'bx' (did you mean 'box'?); the scene's bodies: world, box, pusher");
  EXPECT_EQ(
      error_of(scene, {{Kind::kFriction, "box_gem", 1.0}}),
      "friction of 'box_gem' = 1.0: no geom named 'box_gem' (did you mean 'box_geom'?); the scene's geoms: floor, "
      "box_geom, pusher_geom");
  EXPECT_EQ(
      error_of(scene, {{Kind::kDamping, "slide", 1.0}}).rfind("damping of 'slide' = 1.0: no joint named 'slide'", 0),
      0u);
  EXPECT_EQ(error_of(scene, {{Kind::kFriction, "", -0.1}}), "friction = -0.1: friction must be a finite number >= 0");
  EXPECT_EQ(error_of(scene, {{Kind::kDamping, "", std::nan("")}}),
            "damping = nan: damping must be a finite number >= 0");
  EXPECT_EQ(error_of(scene, {{Kind::kMass, "box", 0.0}}), "mass of 'box' = 0.0: mass must be a finite number > 0");
  EXPECT_EQ(error_of(scene, {{Kind::kMass, "box", std::numeric_limits<double>::infinity()}}),
            "mass of 'box' = inf: mass must be a finite number > 0");
  EXPECT_EQ(error_of(scene, {{Kind::kMass, "", 1.0}}), "mass = 1.0: a mass needs a body's name");
  EXPECT_EQ(error_of(scene, {{Kind::kMass, "world", 1.0}}), "mass of 'world' = 1.0: the world body has no mass to set");
}

// A model value: any writable mjModel array's value, by object and index.
TEST(SceneParams, AModelValueWritesOneValueOfARowOrOfEveryRow) {
  const simloop::Model scene = simloop::pusher_scene();
  const mjModel* s = scene.get();
  const int box = mj_name2id(s, mjOBJ_BODY, "box");
  const int box_geom = mj_name2id(s, mjOBJ_GEOM, "box_geom");
  const simloop::Model wider = simloop::with_scene_params(scene, {{Kind::kModel, "box_geom", 0.3, "geom_friction", 2}});
  for (int g = 0; g < s->ngeom; ++g) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(wider.get()->geom_friction[3 * g + k], g == box_geom && k == 2 ? 0.3 : s->geom_friction[3 * g + k]);
    }
  }
  // Every row; a float array as float.
  const simloop::Model faded = simloop::with_scene_params(scene, {{Kind::kModel, "", 0.25, "geom_rgba", 3}});
  for (int g = 0; g < s->ngeom; ++g) EXPECT_EQ(faded.get()->geom_rgba[4 * g + 3], 0.25f);
  // Every body but the world; a mass recomputes MuJoCo's constants as kMass does.
  const simloop::Model heavy = simloop::with_scene_params(scene, {{Kind::kModel, "", 3.0, "body_mass", 0}});
  EXPECT_EQ(heavy.get()->body_mass[0], 0.0);
  EXPECT_EQ(heavy.get()->body_mass[box], 3.0);
  EXPECT_DOUBLE_EQ(heavy.get()->body_subtreemass[0], 6.0);
  EXPECT_LT(heavy.get()->body_invweight0[2 * box], s->body_invweight0[2 * box]);
  // The scene's own value changes no bit; another changes the run.
  const simloop::RunResult original = run_on(scene);
  for (const simloop::SceneParam& same :
       std::vector<simloop::SceneParam>{{Kind::kModel, "box_geom", 1.0, "geom_friction", 0},
                                        {Kind::kModel, "box", 0.5, "body_mass", 0},
                                        {Kind::kModel, "pusher_slide", 4.0, "dof_damping", 0}}) {
    EXPECT_TRUE(same_bits(run_on(simloop::with_scene_params(scene, {same})), original)) << same.field;
  }
  const simloop::Model slow =
      simloop::with_scene_params(scene, {{Kind::kModel, "push_motor", 2.0, "actuator_gear", 0}});
  EXPECT_LT(run_on(slow).trajectory.at(600, simloop::ChapterColumns::kBoxX),
            original.trajectory.at(600, simloop::ChapterColumns::kBoxX));
}

TEST(SceneParams, AModelValueIsNamedAndRefusedByItsField) {
  const simloop::Model scene = simloop::pusher_scene();
  EXPECT_EQ(simloop::scene_param_column({Kind::kModel, "box_geom", 0.0, "geom_friction", 1}),
            "geom_friction_box_geom_1");
  EXPECT_EQ(simloop::scene_param_column({Kind::kModel, "box", 0.0, "body_mass", 0}), "body_mass_box");
  EXPECT_EQ(simloop::scene_param_column({Kind::kModel, "", 0.0, "geom_rgba", 3}), "geom_rgba_3");
  EXPECT_EQ(simloop::scene_param_column({Kind::kMass, "box", 0.0}), "mass_box");
  EXPECT_EQ(simloop::scene_param_column({Kind::kGravity, "", 0.0}), "gravity");
  EXPECT_EQ(error_of(scene, {{Kind::kModel, "box_geom", 1.0, "geom_fricton", 0}}),
            "geom_fricton[0] of 'box_geom' = 1.0: no mjModel array named 'geom_fricton' (did you mean "
            "'geom_friction'?)");
  EXPECT_EQ(
      error_of(scene, {{Kind::kModel, "box", 1.0, "body_pos", 0}})
          .rfind("body_pos[0] of 'box' = 1.0: mjModel's body_pos is not one a run may vary; these are: body_mass, ", 0),
      0u);
  EXPECT_EQ(error_of(scene, {{Kind::kModel, "box_geom", 1.0, "geom_friction", 3}}),
            "geom_friction[3] of 'box_geom' = 1.0: index must be 0 to 2 (geom_friction holds 3 values per row)");
  EXPECT_EQ(error_of(scene, {{Kind::kModel, "bx", 1.0, "body_mass", 0}})
                .rfind("body_mass[0] of 'bx' = 1.0: no body named 'bx' (did you mean 'box'?)", 0),
            0u);
  EXPECT_EQ(error_of(scene, {{Kind::kModel, "box", -1.0, "body_mass", 0}}),
            "body_mass[0] of 'box' = -1.0: body_mass must be a finite number >= 0");
  EXPECT_EQ(error_of(scene, {{Kind::kModel, "push_motor", std::nan(""), "actuator_gear", 0}}),
            "actuator_gear[0] of 'push_motor' = nan: actuator_gear must be a finite number");
  EXPECT_EQ(error_of(scene, {{Kind::kModel, "box", 1.0, "", 0}}),
            "[0] of 'box' = 1.0: a model value needs a field (an mjModel array's name)");
  EXPECT_NO_THROW((void)simloop::with_scene_params(scene, {{Kind::kModel, "push_motor", -3.0, "actuator_gear", 0}}));
}

}  // namespace

// An object is named as a scenario names it: by name, or (an unnamed one, as
// Gymnasium's actuators are) by the digits of its index.
TEST(SceneParams, AnObjectIsNamedByItsIndexWhereNoObjectHasThatName) {
  const simloop::Model scene = simloop::pusher_scene();
  const mjModel* s = scene.get();
  const int free_joint = 0;  // the box's, unnamed
  ASSERT_EQ(mj_id2name(s, mjOBJ_JOINT, free_joint), nullptr);
  const simloop::Model damped = simloop::with_scene_params(scene, {{Kind::kModel, "0", 0.5, "dof_damping", 0}});
  for (int v = 0; v < s->nv; ++v) {
    EXPECT_EQ(damped.get()->dof_damping[v], s->dof_jntid[v] == free_joint ? 0.5 : s->dof_damping[v]) << v;
  }
  const int box_geom = mj_name2id(s, mjOBJ_GEOM, "box_geom");
  const simloop::Model slippery = simloop::with_scene_params(scene, {{Kind::kFriction, std::to_string(box_geom), 0.1}});
  for (int g = 0; g < s->ngeom; ++g) {
    EXPECT_EQ(slippery.get()->geom_friction[3 * g], g == box_geom ? 0.1 : s->geom_friction[3 * g]);
  }
  EXPECT_EQ(simloop::with_scene_params(scene, {{Kind::kModel, "0", 2.0, "actuator_gear", 0}}).get()->actuator_gear[0],
            2.0);
  EXPECT_EQ(simloop::scene_param_column({Kind::kModel, "0", 0.0, "actuator_gear", 0}), "actuator_gear_0_0");
  EXPECT_EQ(error_of(scene, {{Kind::kModel, "7", 1.0, "actuator_gear", 0}})
                .rfind("actuator_gear[0] of '7' = 1.0: actuator index 7 is out of range", 0),
            0u)
      << error_of(scene, {{Kind::kModel, "7", 1.0, "actuator_gear", 0}});
  EXPECT_EQ(error_of(scene, {{Kind::kMass, "0", 1.0}}), "mass of '0' = 1.0: the world body has no mass to set");
}
