// Scenarios as data: TOML files, names resolved against the scene with
// errors that say what the scene has, and the schedule drawn up front.
#include "simloop/scenario.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/run.hpp"
#include "simloop/shove.hpp"
#include "test_util.hpp"

namespace {

using simloop::InvalidArgument;
using simloop::Scenario;
using simloop::When;

const mjModel* chapter_model() {
  static const simloop::Model model = simloop::pusher_scene();
  return model.get();
}

using test::error_of;

TEST(Scenario, ATomlFileSaysEverythingAsData) {
  const Scenario s = Scenario::from_toml_string(R"(
name = "push it"
scene = "pusht.xml"
timestep = 0.001
duration = 3.0

[[control]]
actuator = "push_x"
value = 0.5

[[control]]
actuator = 1
schedule = [[0.0, 0.0], [1.5, -0.25]]

[[disturbance]]
body = "tblock"
force = [0, 3, 0]
torque = [0, 0, 0.1]
start = 1.0
duration = 0.2

[[disturbance]]
body = "tblock"
newtons = [2, 4]
direction = [3, 4, 0]
random_sign = true
start_fraction = 0.5
steps = 10

[record]
bodies = ["tblock"]
joints = ["slide_x"]
contacts = false
)",
                                                "pusht.toml", "/scenes");
  EXPECT_EQ(s.name, "push it");
  EXPECT_EQ(s.scene, std::filesystem::path("/scenes/pusht.xml"));
  EXPECT_EQ(s.timestep, 0.001);
  EXPECT_EQ(s.length.unit, When::Unit::kSeconds);
  EXPECT_EQ(s.length.value, 3.0);
  ASSERT_EQ(s.controls.size(), 2u);
  EXPECT_EQ(s.controls[1].actuator, "1");
  ASSERT_EQ(s.controls[1].schedule.size(), 2u);
  EXPECT_EQ(s.controls[1].schedule[1].second, -0.25);
  ASSERT_EQ(s.disturbances.size(), 2u);
  EXPECT_EQ(s.disturbances[0].torque[2], 0.1);
  EXPECT_EQ(s.disturbances[0].start.unit, When::Unit::kSeconds);
  EXPECT_DOUBLE_EQ(s.disturbances[1].force[0], 0.6);  // direction normalised
  EXPECT_DOUBLE_EQ(s.disturbances[1].force[1], 0.8);
  EXPECT_TRUE(s.disturbances[1].random_sign);
  EXPECT_EQ(s.disturbances[1].start.unit, When::Unit::kFractionOfRun);
  EXPECT_EQ(s.disturbances[1].duration.to_steps(0.001, 3000), 10);
  EXPECT_EQ(s.record.joints, std::vector<std::string>{"slide_x"});
  EXPECT_FALSE(s.record.contacts);
}

TEST(Scenario, BadFilesNameTheKeyAndWhatIsWrong) {
  const auto error = [](const std::string& text) {
    return error_of([&] { (void)Scenario::from_toml_string(text, "s.toml"); });
  };
  EXPECT_EQ(error("timestep = -1"), "s.toml: timestep: must be a positive number of seconds, got -1.0");
  EXPECT_EQ(error("setps = 5"),
            "s.toml: setps: unknown key (did you mean 'steps'?); known keys: name, scene, timestep, steps, duration, "
            "control, disturbance, record, reset");
  EXPECT_EQ(error("steps = 5\nduration = 1.0"), "s.toml: give only one of duration, steps");
  EXPECT_EQ(error("[[control]]\nvalue = 1"),
            "s.toml: control[0].actuator: missing: name the actuator (or give its index)");
  EXPECT_EQ(error("[[control]]\nactuator = 'a'\nvalue = 'x'"),
            "s.toml: control[0].value: expected a number, got a string");
  EXPECT_EQ(error("[[control]]\nactuator = 'a'\nschedule = [[1.0, 0], [0.5, 1]]"),
            "s.toml: control[0].schedule: times must increase, got 1.0 then 0.5");
  EXPECT_EQ(error("[[disturbance]]\nbody = 'b'\nnewtons = [6, 12]"),
            "s.toml: disturbance[0].direction: missing: newtons draws a strength; direction says which way (a vector)");
  EXPECT_EQ(error("[[disturbance]]\nbody = 'b'\nforce = [1, 2]"),
            "s.toml: disturbance[0].force: expected an array of 3 numbers, got an array of 2");
  EXPECT_EQ(error("[[disturbance]]\nbody = 'b'\nforce = [1, 2, inf]"),
            "s.toml: disturbance[0].force: expected a finite number, got inf");
  EXPECT_EQ(error("[[disturbance]]\nbody = 'b'\nstart = 1.0\nstart_step = 3"),
            "s.toml: disturbance[0]: give only one of start, start_step, start_fraction");
  // Broken TOML: the parser's own words, with the line and column.
  EXPECT_EQ(error("steps = = 3").rfind("s.toml:1:", 0), 0u) << error("steps = = 3");
}

TEST(Scenario, UnknownNamesListWhatTheSceneHasWithADidYouMean) {
  Scenario s = Scenario::chapter();
  s.disturbances[0].body = "bx";
  EXPECT_EQ(
      error_of([&] { (void)simloop::resolve(s, chapter_model()); }),
      "disturbance[0]: no body named 'bx' (did you mean 'box'?); the scene's bodies a force can move: box, pusher");
  s = Scenario::chapter();
  s.controls[0].actuator = "motor";
  EXPECT_EQ(error_of([&] { (void)simloop::resolve(s, chapter_model()); }),
            "control[0]: no actuator named 'motor'; the scene's actuators: push_motor");
  s.controls[0].actuator = "3";
  EXPECT_EQ(error_of([&] { (void)simloop::resolve(s, chapter_model()); }),
            "control[0]: actuator index 3 is out of range: the scene has 1 actuator (0 to 0); the scene's actuators: "
            "push_motor");
  s = Scenario::chapter();
  s.controls.push_back({"0", {{When::steps(0), 0.5}}, {}});  // push_motor again, by index
  EXPECT_EQ(error_of([&] { (void)simloop::resolve(s, chapter_model()); }),
            "control[1]: actuator '0' is already driven by control[0]; give each actuator one control (a schedule "
            "for changes)");
  s = Scenario::chapter();
  s.record.joints = {"pusher_slid"};
  EXPECT_EQ(
      error_of([&] { (void)simloop::resolve(s, chapter_model()); }),
      "record.joints: no joint named 'pusher_slid' (did you mean 'pusher_slide'?); the scene's joints: pusher_slide; "
      "unnamed, by index: 0");
  // A scene whose moving bodies are unnamed (MuJoCo's tendon_arm/arm26.xml):
  // they are listed, and taken, by index.
  const simloop::Model arm = simloop::Model::from_xml_string(
      "<mujoco><worldbody><body><joint type=\"hinge\"/><geom size=\".1\"/>"
      "<body pos=\"0.5 0 0\"><joint type=\"hinge\"/><geom size=\".1\"/></body></body></worldbody></mujoco>",
      "arm");
  s = Scenario::chapter();
  s.controls.clear();
  s.record = simloop::RecordSpec{};
  s.disturbances[0].body = "upper";
  EXPECT_EQ(error_of([&] { (void)simloop::resolve(s, arm.get()); }),
            "disturbance[0]: no body named 'upper'; the scene's bodies a force can move: unnamed, by index: 1, 2");
  s.disturbances[0].body = "3";
  EXPECT_EQ(error_of([&] { (void)simloop::resolve(s, arm.get()); }),
            "disturbance[0]: body index 3 is out of range: the scene has 3 bodies (0 to 2); the scene's bodies a force "
            "can move: unnamed, "
            "by index: 1, 2");
  s.disturbances[0].body = "2";
  EXPECT_EQ(simloop::resolve(s, arm.get()).disturbances.at(0).body, 2);
  s.disturbances[0].body = "0";
  EXPECT_EQ(error_of([&] { (void)simloop::resolve(s, arm.get()); }), "disturbance[0]: the world body cannot be pushed");
}

TEST(Scenario, ResolvesNamesAndIndicesAndDefaultsToFreeBodiesAndActuators) {
  const mjModel* m = chapter_model();
  Scenario s = Scenario::chapter();
  s.controls[0].actuator = "0";
  const simloop::ResolvedScenario r = simloop::resolve(s, m);
  EXPECT_EQ(r.controls[0].actuator, 0);
  EXPECT_EQ(r.disturbances[0].body, mj_name2id(m, mjOBJ_BODY, "box"));
  EXPECT_EQ(r.joints, std::vector<int>{mj_name2id(m, mjOBJ_JOINT, "pusher_slide")});

  Scenario bare;
  const simloop::ResolvedScenario defaults = simloop::resolve(bare, m);
  EXPECT_EQ(defaults.bodies, std::vector<int>{mj_name2id(m, mjOBJ_BODY, "box")});  // the free one
  EXPECT_EQ(defaults.actuators, std::vector<int>{0});
}

TEST(Scenario, AllInARecordListMeansEveryOneTheSceneHas) {
  const mjModel* m = chapter_model();
  const Scenario s = Scenario::from_toml_string("[record]\nbodies = \"all\"\njoints = \"all\"\n");
  EXPECT_TRUE(s.record.all_bodies && s.record.all_joints && !s.record.all_actuators);
  const simloop::ResolvedScenario r = simloop::resolve(s, m);
  // Every body that can move (the box on its free joint, the pusher on its slide), every joint, and only those.
  EXPECT_EQ(r.bodies, (std::vector<int>{mj_name2id(m, mjOBJ_BODY, "box"), mj_name2id(m, mjOBJ_BODY, "pusher")}));
  EXPECT_EQ(r.joints.size(), static_cast<std::size_t>(m->njnt));
  EXPECT_TRUE(r.actuators.empty());
  // A list holding "all" names an object called all; any other string is refused.
  EXPECT_EQ(error_of([&] { (void)simloop::resolve(Scenario::from_toml_string("[record]\njoints = [\"all\"]\n"), m); }),
            "record.joints: no joint named 'all'; the scene's joints: pusher_slide; unnamed, by index: 0");
  EXPECT_EQ(error_of([] { (void)Scenario::from_toml_string("[record]\nsensors = \"every\"\n"); }),
            "<string>: record.sensors: expected an array of names or \"all\", got a string");
}

TEST(Scenario, BodiesFixedToAMovingOneOrMocapMoveAndOnlyJointedOnesArePushed) {
  // A hand fixed to a jointed arm and a mocap target move (a Franka's hand, a
  // Menagerie mocap target); a force moves only what has joints.
  const simloop::Model scene = simloop::Model::from_xml_string(R"(<mujoco><worldbody>
    <body name="arm"><joint type="hinge"/><geom size=".1"/><body name="hand"><geom size=".1"/></body></body>
    <body name="base"><geom size=".1"/></body>
    <body name="target" mocap="true"><geom size=".1"/></body>
  </worldbody></mujoco>)");
  const mjModel* m = scene.get();
  const simloop::ResolvedScenario all = simloop::resolve(Scenario::from_toml_string("[record]\nbodies = \"all\"\n"), m);
  EXPECT_EQ(all.bodies, (std::vector<int>{1, 2, 4}));  // arm, hand, target; not base
  const auto pushing = [&](const char* body) {
    return error_of([&] {
      (void)simloop::resolve(
          Scenario::from_toml_string(std::string("[[disturbance]]\nbody = \"") + body + "\"\nforce = [1, 0, 0]\n"), m);
    });
  };
  EXPECT_EQ(pushing("hand"), test::kNoInvalidArgument);
  EXPECT_EQ(pushing("base"),
            "disturbance[0]: a force on body 'base' moves nothing: it is fixed to the world; the "
            "scene's bodies a force can move: arm, hand");
  EXPECT_EQ(pushing("target"),
            "disturbance[0]: a force on body 'target' moves nothing: it is a mocap body or fixed "
            "to one (moved by mocap_pos); the scene's bodies a force can move: arm, hand");
}

TEST(Schedule, TheChaptersShoveIsOneDisturbanceDrawnAsBefore) {
  const mjModel* m = chapter_model();
  const Scenario s = Scenario::chapter();
  const simloop::ResolvedScenario r = simloop::resolve(s, m);
  for (std::uint64_t seed : {0ull, 1ull, 2ull, 12345ull, ~0ull}) {
    const auto draws = simloop::make_draws(seed);
    const simloop::Schedule schedule = simloop::build_schedule(r, s, 0.002, *draws);
    const simloop::Shove shove = simloop::draw_shove(seed, 2000);
    ASSERT_EQ(schedule.forces.size(), 1u);
    const simloop::Schedule::Force& f = schedule.forces[0];
    EXPECT_EQ(f.wrench[1], shove.force_y()) << seed;  // the same bits
    EXPECT_FALSE(std::signbit(f.wrench[0]));          // +0.0, never -0.0
    EXPECT_EQ(f.wrench[0], 0.0);
    EXPECT_EQ(f.start, shove.start_step);
    EXPECT_EQ(f.end, shove.start_step + shove.num_steps);
    ASSERT_EQ(schedule.control_changes.size(), 1u);
    EXPECT_EQ(schedule.control_changes[0].value, 1.0);
    EXPECT_EQ(schedule.steps, 2000);
  }
}

TEST(Schedule, SecondsBecomeStepsAndAWindowCutShortIsReportedAsCut) {
  const mjModel* m = chapter_model();
  Scenario s = Scenario::chapter();
  s.length = When::seconds(0.12);  // 60 steps of 0.002
  s.controls[0].schedule = {{When::seconds(0.0), 0.5}, {When::seconds(0.05), -1.0}, {When::seconds(10.0), 3.0}};
  const simloop::ResolvedScenario r = simloop::resolve(s, m);
  const auto draws = simloop::make_draws(0);
  const simloop::Schedule schedule = simloop::build_schedule(r, s, 0.002, *draws);
  EXPECT_EQ(schedule.steps, 60);
  ASSERT_EQ(schedule.control_changes.size(), 2u);  // the change at 10 s is past the run
  EXPECT_EQ(schedule.control_changes[1].step, 25);
  EXPECT_EQ(schedule.forces[0].start, 30);
  EXPECT_EQ(schedule.forces[0].end, 60);        // what happened: 30 steps
  EXPECT_EQ(schedule.forces[0].asked_end, 80);  // what was asked: 50
  // A push shorter than half a step pushes for one: it did not vanish at a coarse timestep.
  s.disturbances[0].duration = When::seconds(0.001);
  const simloop::Schedule kick = simloop::build_schedule(simloop::resolve(s, m), s, 0.002, *draws);
  EXPECT_EQ(kick.forces[0].end - kick.forces[0].start, 1);
  EXPECT_EQ(error_of([] {
              (void)Scenario::from_toml_string(
                  "[[disturbance]]\nbody = 'b'\nforce = [1, 0, 0]\n"
                  "duration = 0.0\n",
                  "s.toml");
            }),
            "s.toml: disturbance[0].duration: must be positive (leave it out for one step, a kick)");
  EXPECT_EQ(error_of([] {
              (void)Scenario::from_toml_string(
                  "[[disturbance]]\nbody = 'b'\nforce = [1, 0, 0]\n"
                  "steps = 0\n",
                  "s.toml");
            }),
            "s.toml: disturbance[0].steps: must be positive (leave it out for one step, a kick)");
  s.length = When::seconds(0.0009);
  EXPECT_EQ(error_of([&] { (void)simloop::build_schedule(r, s, 0.002, *draws); }),
            "the run's length (0.0009 s) is less than one step of 0.002 s");
}

TEST(Schedule, AStepFarPastTheRunNeverActs) {
  // schedule_steps holds numbers; one beyond any int64 used to be cast
  // (undefined behaviour) to INT64_MIN, which clamped to step 0.
  const Scenario s = Scenario::from_toml_string(R"(
steps = 5
[[control]]
actuator = "push_motor"
schedule_steps = [[0, 0.1], [1e300, 0.9]]
)");
  const simloop::ResolvedScenario r = simloop::resolve(s, chapter_model());
  const auto draws = simloop::make_draws(0);
  const simloop::Schedule schedule = simloop::build_schedule(r, s, 0.002, *draws);
  ASSERT_EQ(schedule.control_changes.size(), 1u);
  EXPECT_EQ(schedule.control_changes[0].value, 0.1);
}

TEST(Schedule, StepCountsKeepEveryDigit) {
  // Steps were kept as a double: --steps 2^62-1 became 2^62, past kMaxSteps,
  // and the run failed with "steps must be from 1 to ..., got 4611686018427387904".
  EXPECT_EQ(When::steps(simloop::kMaxSteps).to_steps(0.002, 0), simloop::kMaxSteps);
  EXPECT_EQ(When::steps((std::int64_t{1} << 53) + 1).to_steps(0.002, 0), (std::int64_t{1} << 53) + 1);
}

TEST(Scenario, ADirectoryIsNotAScenarioFile) {
  // std::ifstream opens a directory and reads nothing: `--scenario DIR` ran
  // an empty scenario on the chapter's scene and exited 0.
  EXPECT_THROW((void)Scenario::from_toml_file(std::filesystem::temp_directory_path()), simloop::IoError);
}

TEST(Scenario, AnMjcfSceneIsNotAScenarioFileAndSaysWhatToDoWithIt) {
  // toml++ said "Error while parsing root table: expected keys, ..., saw '<'".
  try {
    (void)Scenario::from_toml_file(std::string(SIMLOOP_TEST_SCENES) + "/pusht.xml");
    FAIL() << "an MJCF scene read as a scenario file";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("pusht.xml: an MJCF scene, not a scenario file (TOML): make it a scenario's "
                                         "scene"),
              std::string::npos)
        << e.what();
  }
}

TEST(Scenario, AControlMayComeFromACsvWithARowPerStep) {
  test::TempDir dir;
  test::write_text(dir.path() / "drive.csv", "push_x,other\n0.5,9\n0.5,9\n-0.25,9\n1e-1,9\n");
  test::write_text(dir.path() / "one.csv", "u\n1\n2\n");
  const std::string toml = "steps = 6\n[[control]]\nactuator = 'push_motor'\ncsv = 'drive.csv'\ncolumn = 'push_x'\n";
  const simloop::Scenario s = Scenario::from_toml_string(toml, "s.toml", dir.path());
  ASSERT_EQ(s.controls.size(), 1u);
  EXPECT_EQ(s.controls[0].csv, dir.path() / "drive.csv");  // what a cache of the scenario checks for changes
  const auto& schedule = s.controls[0].schedule;           // only where the value changes
  ASSERT_EQ(schedule.size(), 3u);
  EXPECT_EQ(schedule[0].first.to_steps(0.002, 6), 0);
  EXPECT_EQ(schedule[0].second, 0.5);
  EXPECT_EQ(schedule[1].first.to_steps(0.002, 6), 2);
  EXPECT_EQ(schedule[1].second, -0.25);
  EXPECT_EQ(schedule[2].second, 0.1);
  // Run: rows past the file hold its last value.
  const simloop::ResolvedScenario r = simloop::resolve(s, chapter_model());
  const auto draws = simloop::make_draws(0);
  const simloop::Schedule built = simloop::build_schedule(r, s, 0.002, *draws);
  ASSERT_EQ(built.control_changes.size(), 3u);
  EXPECT_EQ(built.control_changes[2].step, 3);

  EXPECT_EQ(Scenario::from_toml_string("[[control]]\nactuator = 0\ncsv = 'one.csv'\n", "s.toml", dir.path())
                .controls[0]
                .schedule.size(),
            2u);
  EXPECT_TRUE(Scenario::from_toml_string("[[control]]\nactuator = 0\nvalue = 1.0\n").controls[0].csv.empty());
  const auto error = [&](const std::string& text) {
    return error_of([&] { (void)Scenario::from_toml_string(text, "s.toml", dir.path()); });
  };
  EXPECT_EQ(error("[[control]]\nactuator = 0\ncsv = 'drive.csv'\n"),
            "s.toml: control[0].csv: " + (dir.path() / "drive.csv").string() +
                " has 2 columns: name the one to use (column = \"...\")");
  EXPECT_EQ(error("[[control]]\nactuator = 0\ncsv = 'drive.csv'\ncolumn = 'y'\n"),
            "s.toml: control[0].csv: " + (dir.path() / "drive.csv").string() +
                " has no column 'y'; its columns: push_x, other");
  test::write_text(dir.path() / "bad.csv", "u\n1\n 2\n");
  EXPECT_EQ(error("[[control]]\nactuator = 0\ncsv = 'bad.csv'\n"),
            "s.toml: control[0].csv: " + (dir.path() / "bad.csv").string() + ":3: expected a finite number, got ' 2'");
  EXPECT_EQ(error("[[control]]\nactuator = 0\nvalue = 1\ncolumn = 'u'\n"), "s.toml: control[0].column: only with csv");
}

}  // namespace
