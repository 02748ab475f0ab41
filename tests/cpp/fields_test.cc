// fields.hpp: every array of mjModel and mjData by name, its rows and what
// they are, the constraint arrays' rows in use, and the model parameters a
// Sim lets a caller write (in a model of its own).
#include "simloop/fields.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "simloop/chapter_scene.hpp"
#include "simloop/sim.hpp"
#include "test_util.hpp"

namespace {

bool has(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

TEST(Fields, EveryArrayOfMujocosListsIsThereByName) {
  for (const char* name : {"body_mass", "geom_friction", "jnt_qposadr", "actuator_gear", "geom_rgba", "names"}) {
    EXPECT_TRUE(has(simloop::model_field_names(), name)) << name;
  }
  for (const char* name : {"qpos", "xpos", "xquat", "efc_force", "efc_type", "cfrc_ext", "sensordata"}) {
    EXPECT_TRUE(has(simloop::data_field_names(), name)) << name;
  }
  EXPECT_FALSE(has(simloop::data_field_names(), "contact"));  // structs, read through Sim::contacts
}

TEST(Fields, AViewIsTheArrayWithItsRowsAndWhatTheyAre) {
  simloop::Sim sim(simloop::pusher_scene());
  const simloop::FieldView friction = sim.model_field("geom_friction");
  EXPECT_EQ(friction.rows, 3);  // floor, box, pusher
  EXPECT_EQ(friction.cols, 3);
  EXPECT_EQ(friction.rows_are, mjOBJ_GEOM);
  EXPECT_EQ(friction.element, simloop::Element::kFloat64);
  EXPECT_EQ(friction.data, sim.model().get()->geom_friction);
  const simloop::FieldView adr = sim.model_field("jnt_qposadr");
  EXPECT_EQ(adr.element, simloop::Element::kInt32);
  EXPECT_EQ(static_cast<const int*>(adr.data)[1], 7);  // the slide's qpos follows the box's free joint
  const simloop::FieldView gear = sim.model_field("actuator_gear");
  EXPECT_EQ(gear.rows_are, mjOBJ_ACTUATOR);
  EXPECT_EQ(static_cast<const double*>(gear.data)[0], 10.0);
  const simloop::FieldView xpos = sim.data_field("xpos");
  EXPECT_EQ(xpos.rows_are, mjOBJ_BODY);
  EXPECT_EQ(static_cast<const double*>(xpos.data)[3], 0.4);  // the box's x at rest
  const simloop::FieldView qvel = sim.data_field("qvel");
  EXPECT_EQ(qvel.rows_are, mjOBJ_UNKNOWN);
  EXPECT_EQ(qvel.rows_count, "nv");
  EXPECT_EQ(qvel.rows, 7);
}

TEST(Fields, TheConstraintArraysHoldTheRowsInUse) {
  simloop::Sim sim(simloop::pusher_scene());
  sim.step(50);  // the box at rest on the floor: its contacts' constraints
  const simloop::FieldView force = sim.data_field("efc_force");
  EXPECT_EQ(force.rows, sim.data()->nefc);
  EXPECT_EQ(force.rows_count, "nefc");
  EXPECT_GT(force.rows, 0);
  EXPECT_EQ(force.data, sim.data()->efc_force);
}

TEST(Fields, ContactsCarryTheirForcesInTheirFrames) {
  simloop::Sim sim(simloop::pusher_scene());
  sim.step(200);  // at rest: the floor carries the box's weight and the pusher's
  double box_normal = 0;
  for (const simloop::Contact& c : sim.contacts()) {
    EXPECT_NEAR(c.frame[2], 1.0, 1e-9);  // the normal points up, out of the floor
    if (c.geom2 == "box_geom") box_normal += c.force[0];
  }
  EXPECT_NEAR(box_normal, 0.5 * 9.81, 1e-3);  // the box's weight, spread over its corners
}

TEST(Fields, TheForcesMujocoFillsAfterTheConstraintsAreFilledWhenRead) {
  simloop::Sim sim(simloop::pusher_scene());
  sim.step(200);  // at rest: the floor carries the box's weight
  EXPECT_TRUE(simloop::filled_after_constraint("cfrc_ext"));
  EXPECT_FALSE(simloop::filled_after_constraint("xpos"));
  EXPECT_EQ(sim.data()->cfrc_ext[6 + 5], 0.0);  // no step fills it (mj_rnePostConstraint)
  const simloop::FieldView cfrc_ext = sim.data_field("cfrc_ext");
  // (torque, force) per body: the box's force from the floor carries its weight.
  EXPECT_NEAR(static_cast<const double*>(cfrc_ext.data)[6 + 5], 0.5 * 9.81, 1e-3);
  const simloop::FieldView cacc = sim.data_field("cacc");  // (gravity's, as MuJoCo counts it)
  EXPECT_NEAR(static_cast<const double*>(cacc.data)[6 + 5], 9.81, 1e-3);
}

TEST(Fields, SubtreeVelocitiesAreFilledWhenRead) {
  // mj_subtreeVel fills subtree_linvel and subtree_angmom; no step calls it.
  // A named read gives MuJoCo's values, as a recorded column does
  // (fill_derived), not the zeros or older values the step leaves.
  simloop::Sim sim(simloop::pusher_scene());
  sim.set_ctrl(1.0);
  sim.step(300);  // the pusher has reached the box and pushes it
  EXPECT_TRUE(simloop::filled_on_request("subtree_angmom"));
  EXPECT_FALSE(simloop::filled_on_request("cvel"));
  const mjModel* m = sim.model().get();
  mjData* expected = mj_makeData(m);
  mj_copyData(expected, m, sim.data());
  mj_subtreeVel(m, expected);
  for (const char* name : {"subtree_linvel", "subtree_angmom"}) {
    const simloop::FieldView f = sim.data_field(name);
    const auto* read = static_cast<const double*>(f.data);
    const double* want = std::string(name) == "subtree_linvel" ? expected->subtree_linvel : expected->subtree_angmom;
    for (int i = 0; i < 3 * m->nbody; ++i) EXPECT_EQ(read[i], want[i]) << name << "[" << i << "]";
  }
  EXPECT_GT(std::abs(expected->subtree_linvel[3 * 1]), 0.01);  // the box moves: not zeros that agree
  mj_deleteData(expected);
}

TEST(Fields, AWritableParameterIsTheSimsOwnAndChangesItsRun) {
  const simloop::Model shared = simloop::pusher_scene();
  simloop::Sim sim(shared);
  const simloop::Sim untouched(shared);
  const mjModel* before = sim.model().get();
  const simloop::FieldView mass = sim.writable_model_field("body_mass");
  EXPECT_NE(sim.model().get(), before);  // a copy of its own
  static_cast<double*>(mass.data)[1] = 2.0;
  EXPECT_EQ(shared.get()->body_mass[1], 0.5);                        // the shared model is as it was
  EXPECT_EQ(sim.writable_model_field("body_mass").data, mass.data);  // and copied once only
  sim.set_timestep(0.001);
  EXPECT_EQ(sim.model().get()->body_mass[1], 2.0);  // a timestep keeps the written mass
  const simloop::Sim copied(sim);
  EXPECT_NE(copied.model().get(), sim.model().get());  // a copy's writes are its own...
  EXPECT_EQ(copied.model().get()->body_mass[1], 2.0);  // ...from the same values
  EXPECT_EQ(untouched.model().get()->body_mass[1], 0.5);

  // Friction: a box on a frictionless floor keeps sliding (MuJoCo takes the
  // larger of two geoms' frictions: both the floor's and the box's go).
  simloop::Sim slippery(shared), rough(shared);
  double* friction = static_cast<double*>(slippery.writable_model_field("geom_friction").data);
  friction[0] = friction[3] = 0.0;
  for (simloop::Sim* s : {&slippery, &rough}) {
    s->data()->qvel[0] = 1.0;  // the box slides along x at 1 m/s
    s->step(100);
  }
  EXPECT_GT(slippery.data()->qvel[0], 0.99);
  EXPECT_LT(rough.data()->qvel[0], 0.1);
}

TEST(Fields, TheWritableNamesAreTheWritableArraysInTheirOrder) {
  const std::vector<std::string> writable = simloop::writable_model_field_names();
  EXPECT_EQ(writable.front(), "body_mass");
  for (const std::string& name : simloop::model_field_names()) {
    EXPECT_EQ(std::count(writable.begin(), writable.end(), name), simloop::model_field_writable(name) ? 1 : 0) << name;
  }
}

TEST(Fields, UnknownAndReadOnlyArraysAreRefusedNamingThem) {
  simloop::Sim sim(simloop::pusher_scene());
  EXPECT_EQ(test::error_of([&] { (void)sim.model_field("geom_fricton"); }),
            "no mjModel array named 'geom_fricton' (did you mean 'geom_friction'?)");
  EXPECT_EQ(test::error_of([&] { (void)sim.data_field("xposs"); }),
            "no mjData array named 'xposs' (did you mean 'xpos'?)");
  EXPECT_EQ(test::error_of([&] { (void)sim.data_field("contact"); }),
            "mjData's contact array holds structs, not numbers: read a Sim's contacts (with their forces) instead");
  const mjModel* before = sim.model().get();
  EXPECT_NE(test::error_of([&] { (void)sim.writable_model_field("geom_size"); }).find("geom_size is read-only here"),
            std::string::npos);
  EXPECT_EQ(test::error_of([&] { (void)sim.writable_model_field("geom_sise"); }),
            "no mjModel array named 'geom_sise' (did you mean 'geom_size'?)");
  EXPECT_EQ(sim.model().get(), before);  // nothing copied for a refusal
}

}  // namespace
