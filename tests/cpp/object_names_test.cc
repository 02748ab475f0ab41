// object_names.hpp: the one wording of every lookup's error (what the scene
// has, by name and by index) and the one rule for a likely typo.
#include "simloop/object_names.hpp"

#include <gtest/gtest.h>

#include <string>

#include "simloop/errors.hpp"
#include "simloop/model.hpp"

namespace {

// Bodies 1 and 4 named, 2, 3, 5, 6 and 7 not; 3 geoms, none named; no actuator.
const mjModel* scene() {
  static const simloop::Model model = simloop::Model::from_xml_string(R"(<mujoco><worldbody>
    <body name="a"><freejoint/><geom size="0.1"/>
      <body><body><body name="d"><body><body><body/></body></body></body></body></body>
    </body>
    <body pos="1 0 0"><geom size="0.1"/></body>
    <geom type="plane" size="1 1 0.1"/>
  </worldbody></mujoco>)");
  return model.get();
}

bool moves(const mjModel* m, int body) { return m->body_dofnum[body] > 0; }

TEST(ObjectNames, AnUnknownNameListsTheNamesAndTheUnnamedByIndexInRuns) {
  const mjModel* m = scene();
  EXPECT_EQ(simloop::unknown_name_message(m, mjOBJ_BODY, "dd"),
            "no body named 'dd' (did you mean 'd'?); the scene's bodies: world, a, d; unnamed, by index: 2, 3, 5 to 8");
  EXPECT_EQ(simloop::unknown_name_message(m, mjOBJ_GEOM, "floor"),
            "no geom named 'floor'; the scene's geoms: unnamed, by index: 0 to 2");
  EXPECT_EQ(simloop::unknown_name_message(m, mjOBJ_ACTUATOR, "motor"),
            "no actuator named 'motor'; the scene has no actuators");
  EXPECT_EQ(simloop::unknown_name_message(m, mjOBJ_BODY, "zz", {"bodies that can move", moves}),
            "no body named 'zz'; the scene's bodies that can move: a");
  EXPECT_EQ(simloop::unknown_name_message(m, mjOBJ_BODY, "zz",
                                          {"bodies that can fly", [](const mjModel*, int) { return false; }}),
            "no body named 'zz'; the scene has no bodies that can fly");
}

// How a scenario names an object: a name first, else the digits of an index.
TEST(ObjectNames, AnObjectIsItsNameElseTheDigitsOfItsIndex) {
  const simloop::Model named_one = simloop::Model::from_xml_string(R"(<mujoco><worldbody>
    <body name="1"><freejoint/><geom size="0.1"/></body>
    <body><freejoint/><geom size="0.1"/></body>
  </worldbody></mujoco>)");
  const mjModel* m = named_one.get();
  EXPECT_EQ(simloop::object_id_or_index(m, mjOBJ_BODY, "1"), 1);   // the body named '1' (it is body 1)
  EXPECT_EQ(simloop::object_id_or_index(m, mjOBJ_BODY, "2"), 2);   // no body named '2': body 2
  EXPECT_EQ(simloop::object_id_or_index(m, mjOBJ_BODY, "02"), 2);  // digits, as --body 02 reads
  EXPECT_EQ(simloop::object_id_or_index(m, mjOBJ_BODY, "world"), 0);
  const auto error = [&](const std::string& name) {
    try {
      (void)simloop::object_id_or_index(m, mjOBJ_BODY, name);
    } catch (const simloop::InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(error("3").rfind("body index 3 is out of range: the scene has 3 bodies (0 to 2)", 0), 0u) << error("3");
  EXPECT_EQ(error("99999999999999999999").rfind("body index 99999999999999999999 is out of range", 0), 0u)
      << error("99999999999999999999");
  EXPECT_EQ(error("-1").rfind("no body named '-1'", 0), 0u) << error("-1");
  EXPECT_EQ(error("").rfind("no body named ''", 0), 0u) << error("");
}

TEST(ObjectNames, AnIndexOutOfRangeSaysHowManyTheSceneHas) {
  const mjModel* m = scene();
  EXPECT_EQ(
      simloop::index_out_of_range_message(m, mjOBJ_GEOM, "3"),
      "geom index 3 is out of range: the scene has 3 geoms (0 to 2); the scene's geoms: unnamed, by index: 0 to 2");
  EXPECT_EQ(simloop::index_out_of_range_message(m, mjOBJ_ACTUATOR, "0"),
            "actuator index 0 is out of range: the scene has no actuators");
  EXPECT_EQ(simloop::checked_object_index(m, mjOBJ_BODY, 8), 8);
  EXPECT_THROW((void)simloop::checked_object_index(m, mjOBJ_BODY, -1), simloop::InvalidArgument);
  try {
    (void)simloop::object_id(m, mjOBJ_BODY, "A");
    FAIL() << "found a body named 'A'";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("no body named 'A' (did you mean 'a'?); the scene's bodies: world", 0), 0u)
        << e.what();
  }
}

TEST(ObjectNames, AKindIsOneOfTheWordsOrAnErrorListingThem) {
  EXPECT_EQ(simloop::object_type_of_kind("body"), mjOBJ_BODY);
  EXPECT_EQ(simloop::object_type_of_kind("actuator"), mjOBJ_ACTUATOR);
  try {
    (void)simloop::object_type_of_kind("bodies");
    FAIL() << "'bodies' was taken";
  } catch (const simloop::InvalidArgument& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("kind must be one of 'body', 'joint', ", 0), 0u) << message;
    EXPECT_NE(message.find(", got 'bodies'"), std::string::npos) << message;
  }
}

TEST(DidYouMean, SuggestsOnlyLikelyTypos) {
  EXPECT_EQ(simloop::did_you_mean("tblok", {"tblock", "pusher"}), "tblock");
  EXPECT_EQ(simloop::did_you_mean("PUSHER", {"tblock", "pusher"}), "pusher");
  EXPECT_EQ(simloop::did_you_mean("floor", {"tblock", "pusher"}), "");
  EXPECT_EQ(simloop::did_you_mean("bodys", {"bodies", "joints"}), "bodies");  // two edits in six letters
  EXPECT_EQ(simloop::did_you_mean("box", {"bar", "pusher"}), "");             // not two in three
  EXPECT_EQ(simloop::did_you_mean("x", {}), "");
}

}  // namespace
