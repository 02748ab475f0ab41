#include "simloop/model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include "expected.hpp"
#include "simloop/errors.hpp"
#include "simloop/run.hpp"
#include "simloop/sim.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

std::string scene_with(const std::string& from, const std::string& to) {
  std::string xml(simloop::pusher_scene_xml());
  const auto at = xml.find(from);
  if (at == std::string::npos) std::abort();
  return xml.replace(at, from.size(), to);
}

template <class Exception, class F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const Exception& e) {
    return e.what();
  }
  ADD_FAILURE() << "no exception thrown";
  return {};
}

TEST(Model, ChapterSceneLoadsWithTheChaptersLayout) {
  const simloop::Model model = simloop::pusher_scene();
  const mjModel* m = model.get();
  EXPECT_EQ(m->nq, 8);  // box free joint 7 + pusher slide 1: "eight numbers"
  EXPECT_EQ(m->nv, 7);
  EXPECT_EQ(m->nu, 1);
  const simloop::ChapterLayout at = simloop::chapter_layout(model);
  EXPECT_EQ(at.box_qposadr, 0);
  EXPECT_EQ(at.box_dofadr, 0);
  EXPECT_EQ(at.pusher_qposadr, 7);
  EXPECT_EQ(at.pusher_dofadr, 6);
  EXPECT_EQ(at.pusher_body, mj_name2id(m, mjOBJ_BODY, "pusher"));
  EXPECT_EQ(m->actuator_gear[0], 10.0);
  EXPECT_EQ(m->actuator_ctrllimited[0], 1);  // autolimits turned ctrlrange on
  EXPECT_EQ(model.timestep(), 0.002);        // MuJoCo's default, as in the chapter
}

TEST(Model, WithTimestepCopiesAndLeavesTheOriginal) {
  const simloop::Model model = simloop::pusher_scene();
  const simloop::Model coarse = model.with_timestep(0.05);
  EXPECT_EQ(coarse.timestep(), 0.05);
  EXPECT_EQ(model.timestep(), 0.002);
  EXPECT_NE(coarse.get(), model.get());
  for (double bad : {0.0, -0.002, std::nan(""), std::numeric_limits<double>::infinity()}) {
    const std::string msg = message_of<simloop::InvalidArgument>([&] { (void)model.with_timestep(bad); });
    EXPECT_NE(msg.find("timestep"), std::string::npos) << msg;
  }
}

TEST(Model, DataFitsModelsOfTheSameStructureOnly) {
  const simloop::Model model = simloop::pusher_scene();
  const simloop::Data data(model);
  EXPECT_TRUE(data.fits(model.with_timestep(0.05)));
  const simloop::Model bigger = simloop::Model::from_xml_string(scene_with(
      "</worldbody>", "<body name=\"extra\" pos=\"1 1 1\"><freejoint/><geom size=\"0.1\"/></body></worldbody>"));
  EXPECT_FALSE(data.fits(bigger));
  simloop::Data mismatched(bigger);
  EXPECT_THROW((void)simloop::run(model, simloop::RunConfig{}, mismatched), simloop::InvalidArgument);
}

TEST(Model, MissingPiecesAreNamed) {
  // Any scene loads (scenarios run on any scene); the chapter's loop, which
  // reads the box and the pusher, refuses one without them, naming what is
  // missing (once at load: layout(); again in run()).
  const simloop::Model crate =
      simloop::Model::from_xml_string(scene_with("name=\"box\"", "name=\"crate\""), "test.xml");
  EXPECT_NE(simloop::chapter_layout_missing(crate), "");
  EXPECT_NE(message_of<simloop::InvalidArgument>([&] {
              (void)simloop::chapter_layout(crate);
            }).find("test.xml: the model has no body named \"box\""),
            std::string::npos);
  EXPECT_EQ(message_of<simloop::InvalidArgument>([&] { (void)simloop::run(crate, simloop::RunConfig{}); }),
            simloop::chapter_layout_missing(crate));
  EXPECT_NE(message_of<simloop::InvalidArgument>([] {
              (void)simloop::chapter_layout(
                  simloop::Model::from_xml_string(scene_with("<freejoint/>", "<joint type=\"slide\"/>")));
            }).find("body \"box\" must have exactly one joint, a free joint"),
            std::string::npos);
  const std::string no_actuator =
      scene_with("<motor name=\"push_motor\" joint=\"pusher_slide\" gear=\"10\" ctrlrange=\"-1 1\"/>", "");
  EXPECT_NE(message_of<simloop::InvalidArgument>([&] {
              (void)simloop::chapter_layout(simloop::Model::from_xml_string(no_actuator));
            }).find("no actuator"),
            std::string::npos);
  const std::string ball = scene_with("type=\"slide\" axis=\"1 0 0\"", "type=\"ball\"");
  EXPECT_NE(message_of<simloop::InvalidArgument>([&] {
              (void)simloop::chapter_layout(simloop::Model::from_xml_string(ball));
            }).find("slide or hinge"),
            std::string::npos);
  EXPECT_EQ(simloop::chapter_layout_missing(simloop::pusher_scene()), "");
}

TEST(Model, AFileThatIsNotXmlSaysSoNotWhatTheXmlParserMadeOfIt) {
  const std::string scenario = std::string(SIMLOOP_TEST_SCENES) + "/pusht.toml";
  EXPECT_EQ(message_of<simloop::MujocoError>([&] { (void)simloop::Model::from_file(scenario); }),
            scenario +
                ": not an MJCF scene (its text begins with '#', not '<'); a scenario file (TOML) runs as a "
                "scenario (--scenario, simloop.Scenario.from_file)");
}

TEST(Model, InvalidXmlRaisesMujocosOwnMessageAndWritesNoLog) {
  test::TempDir dir;
  test::in_directory(dir.path(), [] {
    const std::string msg = message_of<simloop::MujocoError>(
        [] { (void)simloop::Model::from_xml_string("<mujoco><worldbody><body></mujoco>", "broken.xml"); });
    EXPECT_EQ(msg.rfind("broken.xml: XML parse error", 0), 0u) << msg;
    EXPECT_NE(msg.find("XML_ERROR_MISMATCHED_ELEMENT"), std::string::npos) << msg;
    // Schema errors go through MuJoCo's parser too: an attribute no
    // MuJoCo knows.
    const std::string unknown = scene_with("<light pos=\"0 0 3\"", "<light shine=\"1\" pos=\"0 0 3\"");
    const std::string msg2 = message_of<simloop::MujocoError>([&] { (void)simloop::Model::from_xml_string(unknown); });
    EXPECT_NE(msg2.find("shine"), std::string::npos) << msg2;
  });
  EXPECT_FALSE(fs::exists(dir.path() / "MUJOCO_LOG.TXT"));
}

TEST(Model, ASceneForNewerMujocoSaysHowToGetIt) {
  // implicitfast came in MuJoCo 2.3.3: 2.2 refuses the word, and the message
  // says which MuJoCo this is and how to build on the other.
  SIMLOOP_EXPECTED(bool, refused, "errors.implicitfast_refused");
  const std::string xml = scene_with("<compiler autolimits=\"true\"/>",
                                     "<compiler autolimits=\"true\"/><option integrator=\"implicitfast\"/>");
  if (!refused) {
    EXPECT_NE(simloop::Model::from_xml_string(xml, "new.xml").get(), nullptr);
    return;
  }
  const std::string msg =
      message_of<simloop::MujocoError>([&] { (void)simloop::Model::from_xml_string(xml, "new.xml"); });
  EXPECT_NE(msg.find("implicitfast"), std::string::npos) << msg;
  EXPECT_NE(msg.find(std::string("this simloop runs MuJoCo ") + mj_versionString() +
                     "; for a scene written for newer "
                     "MuJoCo, build it on the mujoco package: SIMLOOP_MUJOCO=pypi scripts/run.sh)"),
            std::string::npos)
      << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

TEST(Model, FromFile) {
  test::TempDir dir;
  const fs::path path = dir.path() / "scene.xml";
  test::write_text(path, std::string(simloop::pusher_scene_xml()));
  const simloop::Model model = simloop::Model::from_file(path.string());
  EXPECT_EQ(model.get()->nq, 8);
  const std::string msg =
      message_of<simloop::IoError>([&] { (void)simloop::Model::from_file((dir.path() / "nope.xml").string()); });
  EXPECT_NE(msg.find("nope.xml: cannot open (No such file or directory)"), std::string::npos) << msg;
  // A directory opens for reading on Linux: MuJoCo then said "XML parse error 5".
  EXPECT_EQ(message_of<simloop::IoError>([&] { (void)simloop::Model::from_file(dir.path().string()); }),
            dir.path().string() + ": is a directory, not an MJCF file");
}

TEST(Model, MujocoErrorsBecomeExceptionsAndWriteNoLog) {
  // By default MuJoCo 2.2 would log, wait for Enter and exit on each of these.
  test::TempDir dir;
  test::in_directory(dir.path(), [] {
    // While compiling: a stack far too small for the forward pass that
    // compilation runs.
    // (2.2 sizes it with nstack, 3.x with memory; the words differ too.)
    SIMLOOP_EXPECTED(std::string, small_stack_size, "errors.small_stack_size");
    SIMLOOP_EXPECTED(std::string, small_stack_message, "errors.small_stack_message");
    const std::string small_stack =
        scene_with("<compiler autolimits=\"true\"/>", "<compiler autolimits=\"true\"/>" + small_stack_size);
    const std::string msg =
        message_of<simloop::MujocoError>([&] { (void)simloop::Model::from_xml_string(small_stack, "tiny.xml"); });
    EXPECT_EQ(msg.rfind("tiny.xml: " + small_stack_message, 0), 0u) << msg;

    // While stepping: mj_step raises mju_error for an integrator it does not
    // know. (Model is read-only by design; the test reaches past that.)
    const simloop::Model broken = simloop::pusher_scene().with_timestep(0.002);
    const_cast<mjModel*>(broken.get())->opt.integrator = 99;
    const std::string step_msg =
        message_of<simloop::MujocoError>([&] { (void)simloop::run(broken, simloop::RunConfig{}); });
    EXPECT_NE(step_msg.find("integrator"), std::string::npos) << step_msg;

    // The process carries on, and a good model still runs.
    simloop::RunConfig smoke;
    smoke.smoke = true;
    EXPECT_EQ(simloop::run(simloop::pusher_scene(), smoke).metrics.steps, 300);
  });
  EXPECT_FALSE(fs::exists(dir.path() / "MUJOCO_LOG.TXT"));
}

TEST(Model, ReportsTheLinkedMujocoVersion) {
  // As MuJoCo spells it, whatever the version's number encoding (222 for
  // 2.2.2, 3017000 for 3.17.0).
  EXPECT_EQ(simloop::mujoco_version(), std::string("MuJoCo ") + mj_versionString());
  EXPECT_EQ(mj_version() >= 3000000
                ? std::to_string(mj_version() / 1000000) + "." + std::to_string(mj_version() / 1000 % 1000) + "." +
                      std::to_string(mj_version() % 1000)
                : std::to_string(mj_version() / 100) + "." + std::to_string(mj_version() / 10 % 10) + "." +
                      std::to_string(mj_version() % 10),
            mj_versionString());
}

}  // namespace
