// run_schedule, the scenario loop with its recorder, on scenes that are not
// the chapter's: PushT, a walker, an arm and a puck.
#include "simloop/recorder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "simloop/chapter_scene.hpp"
#include "simloop/episode.hpp"
#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"
#include "test_util.hpp"

namespace {

struct Loaded {
  std::shared_ptr<mjModel> model;
  std::shared_ptr<mjData> data;
};

// The scene through MuJoCo directly: the loop needs nothing but mjModel.
Loaded load(const char* file) {
  (void)simloop::pusher_scene();  // installs simloop's MuJoCo handlers
  char error[512] = "";
  mjModel* m = mj_loadXML((std::string(SIMLOOP_TEST_SCENES) + "/" + file).c_str(), nullptr, error, sizeof error);
  if (m == nullptr) throw std::runtime_error(error);
  return {std::shared_ptr<mjModel>(m, mj_deleteModel), std::shared_ptr<mjData>(mj_makeData(m), mj_deleteData)};
}

struct PushtRun {
  simloop::Scenario scenario;
  simloop::RunRecord result;
  int column(const std::string& name) const {
    for (size_t i = 0; i < result.columns.size(); ++i) {
      if (result.columns[i].name == name) return static_cast<int>(i);
    }
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
  double at(std::int64_t row, const std::string& name) const { return result.trajectory.at(row, column(name)); }
};

PushtRun run_file(const char* toml, std::uint64_t seed, std::int64_t record_every = 1) {
  PushtRun r;
  r.scenario = simloop::Scenario::from_toml_file(std::string(SIMLOOP_TEST_SCENES) + "/" + toml);
  const Loaded scene = load(r.scenario.scene.filename().c_str());
  const simloop::ResolvedScenario resolved = simloop::resolve(r.scenario, scene.model.get());
  const auto draws = simloop::make_draws(seed);
  const simloop::Schedule schedule = simloop::build_schedule(resolved, r.scenario, scene.model->opt.timestep, *draws);
  r.result = simloop::run_schedule(scene.model.get(), scene.data.get(), resolved, schedule, record_every);
  return r;
}

PushtRun run_pusht(std::uint64_t seed, std::int64_t record_every = 1, simloop::RowSink* sink = nullptr) {
  static const Loaded scene = load("pusht.xml");
  PushtRun r;
  r.scenario = simloop::Scenario::from_toml_file(std::string(SIMLOOP_TEST_SCENES) + "/pusht.toml");
  const simloop::ResolvedScenario resolved = simloop::resolve(r.scenario, scene.model.get());
  const auto draws = simloop::make_draws(seed);
  const simloop::Schedule schedule = simloop::build_schedule(resolved, r.scenario, scene.model->opt.timestep, *draws);
  r.result = simloop::run_schedule(scene.model.get(), scene.data.get(), resolved, schedule, record_every, sink);
  return r;
}

TEST(ScenarioRun, ColumnsAreNamedFromTheScene) {
  const PushtRun r = run_pusht(0);
  std::vector<std::string> names;
  for (const simloop::Column& c : r.result.columns) names.push_back(c.name);
  const std::vector<std::string> expected = {
      "step",        "time",        "push_x_ctrl", "push_y_ctrl", "tblock_fx",   "tblock_fy",    "tblock_fz",
      "tblock_tx",   "tblock_ty",   "tblock_tz",   "tblock_x",    "tblock_y",    "tblock_z",     "tblock_qw",
      "tblock_qx",   "tblock_qy",   "tblock_qz",   "tblock_vx",   "tblock_vy",   "tblock_vz",    "tblock_wx",
      "tblock_wy",   "tblock_wz",   "pusher_x",    "pusher_y",    "pusher_z",    "pusher_qw",    "pusher_qx",
      "pusher_qy",   "pusher_qz",   "pusher_vx",   "pusher_vy",   "pusher_vz",   "pusher_wx",    "pusher_wy",
      "pusher_wz",   "slide_x_pos", "slide_x_vel", "slide_y_pos", "slide_y_vel", "push_x_force", "push_y_force",
      "tblock_pos0", "tblock_pos1", "tblock_pos2", "tip_x",       "contacts"};
  EXPECT_EQ(names, expected);
  EXPECT_EQ(r.result.rows, 1001);  // 2.0 s of 0.002 s steps, plus the final state
  EXPECT_EQ(r.result.trajectory.rows(), 1001);
}

TEST(ScenarioRun, TheScheduleIsWhatTheStepsGot) {
  const PushtRun r = run_pusht(0);
  // push_y: 0 until 0.5 s (step 250), 0.4 until 1.0 s, then 2.0 asked, 1.0 applied (ctrlrange).
  EXPECT_EQ(r.at(249, "push_y_ctrl"), 0.0);
  EXPECT_EQ(r.at(250, "push_y_ctrl"), 0.4);
  EXPECT_EQ(r.at(499, "push_y_ctrl"), 0.4);
  EXPECT_EQ(r.at(500, "push_y_ctrl"), 1.0);
  EXPECT_EQ(r.at(999, "push_x_ctrl"), 0.8);
  EXPECT_TRUE(std::isnan(r.at(1000, "push_x_ctrl")));  // the final row has no inputs
  // The bump: steps 600 to 649, along +-y, 0.5 to 1.5 N; zero before and after.
  const double fy = r.at(600, "tblock_fy");
  EXPECT_GE(std::fabs(fy), 0.5);
  EXPECT_LT(std::fabs(fy), 1.5);
  EXPECT_EQ(r.at(599, "tblock_fy"), 0.0);
  EXPECT_EQ(r.at(649, "tblock_fy"), fy);
  EXPECT_EQ(r.at(650, "tblock_fy"), 0.0);
  EXPECT_EQ(r.at(620, "tblock_fx"), 0.0);
  EXPECT_FALSE(std::signbit(r.at(620, "tblock_fx")));
  // The motors did push: the pusher moved in both x and y, and the T moved.
  EXPECT_GT(r.at(1000, "slide_x_pos"), 0.05);
  EXPECT_GT(r.at(1000, "slide_y_pos"), 0.01);
  EXPECT_GT(std::hypot(r.at(1000, "tblock_x") - 0.2, r.at(1000, "tblock_y")), 0.01);
}

TEST(ScenarioRun, DerivedQuantitiesDoNotLagTheStateTheyBelongTo) {
  // Body poses and sensors are read after mj_step computed them for the
  // row's state; joint positions before the step. If either lagged, these
  // would differ by a step's worth of motion.
  const PushtRun r = run_pusht(3);
  for (std::int64_t row : {0, 1, 300, 650, 1000}) {
    EXPECT_EQ(r.at(row, "tip_x"), r.at(row, "slide_x_pos")) << row;     // jointpos sensor vs qpos
    EXPECT_EQ(r.at(row, "tblock_pos0"), r.at(row, "tblock_x")) << row;  // framepos sensor vs xpos
    EXPECT_EQ(r.at(row, "tblock_pos2"), r.at(row, "tblock_z")) << row;
  }
  EXPECT_NE(r.at(300, "slide_x_pos"), r.at(301, "slide_x_pos"));  // it does move each step
}

TEST(ScenarioRun, SameSeedSameBitsOtherSeedOtherBump) {
  const PushtRun a = run_pusht(7), b = run_pusht(7), c = run_pusht(8);
  ASSERT_EQ(a.result.trajectory.rows(), b.result.trajectory.rows());
  const size_t n = static_cast<size_t>(a.result.trajectory.rows() * a.result.trajectory.columns());
  EXPECT_EQ(std::memcmp(a.result.trajectory.data(), b.result.trajectory.data(), n * sizeof(double)), 0);
  EXPECT_NE(a.at(600, "tblock_fy"), c.at(600, "tblock_fy"));
  EXPECT_EQ(a.result.schedule.forces[0].wrench[1], a.at(600, "tblock_fy"));
}

TEST(ScenarioRun, RecordEveryKeepsTheSameRowsAndTheFinalState) {
  const PushtRun all = run_pusht(1, 1), some = run_pusht(1, 7);
  EXPECT_EQ(some.result.trajectory.rows(), 1000 / 7 + 1 + 1);
  for (std::int64_t i = 0; i + 1 < some.result.trajectory.rows(); ++i) {
    const size_t w = static_cast<size_t>(all.result.trajectory.columns());
    EXPECT_EQ(std::memcmp(some.result.trajectory.row(i), all.result.trajectory.row(7 * i), w * sizeof(double)), 0) << i;
  }
  EXPECT_EQ(some.at(some.result.trajectory.rows() - 1, "step"), 1000);
}

TEST(ScenarioRun, AWalkerUnderATorqueScheduleRecordsTheDefaults) {
  const PushtRun r = run_file("walker.toml", 0);
  EXPECT_EQ(r.result.timestep, 0.004);  // the scene's own
  EXPECT_EQ(r.result.rows, 751);
  // Defaults: the free body and every actuator (ctrl and force).
  for (const char* name : {"torso_z", "torso_wz", "hip_left_ctrl", "knee_right_ctrl", "knee_right_force", "torso_tz"}) {
    r.column(name);
  }
  EXPECT_EQ(r.at(0, "hip_left_ctrl"), 0.5);
  EXPECT_EQ(r.at(130, "hip_left_ctrl"), -0.5);  // 0.5 s at 0.004 s a step is step 125
  EXPECT_EQ(r.at(400, "knee_left_ctrl"), 0.2);
  EXPECT_EQ(r.at(10, "knee_right_ctrl"), -0.3);  // actuator 3, by index
  EXPECT_EQ(r.at(250, "torso_tz"), 2.0);         // the twist, 1.0 s to 1.05 s
  EXPECT_EQ(r.at(262, "torso_tz"), 0.0);
  EXPECT_LT(r.at(750, "torso_z"), 0.8);  // it fell
  EXPECT_NE(r.at(300, "knee_right_force"), 0.0);
}

TEST(ScenarioRun, AnArmPushesAPuckOnTwoSlides) {
  const PushtRun r = run_file("arm_push.toml", 0);
  double most_contacts = 0;
  for (std::int64_t i = 0; i < r.result.rows; ++i) most_contacts = std::max(most_contacts, r.at(i, "contacts"));
  EXPECT_GT(most_contacts, 0);
  const std::int64_t last = r.result.rows - 1;
  EXPECT_GT(std::hypot(r.at(last, "puck_x_pos"), r.at(last, "puck_y_pos")), 0.01);  // the puck moved
  EXPECT_NEAR(r.at(last, "puck_x_pos"), r.at(last, "puck_x") - 0.3, 1e-12);         // joint vs body: the same motion
  EXPECT_EQ(r.at(420, "puck_fy"), -0.5);                                            // 2.0 s to 2.2 s: steps 400 to 439
  EXPECT_EQ(r.at(440, "puck_fy"), 0.0);
}

}  // namespace

TEST(ScenarioRun, ATendonsLengthAndRateAreRecordedForTheRowsState) {
  // A fixed tendon over two slides: its length is their positions' sum, its rate their velocities'.
  const simloop::Model scene = simloop::Model::from_xml_string(R"(<mujoco>
  <worldbody>
    <body><joint name="a" type="slide" axis="1 0 0"/><geom size="0.1" mass="1"/>
      <body><joint name="b" type="slide" axis="0 1 0"/><geom size="0.1" mass="1"/></body></body>
  </worldbody>
  <tendon><fixed name="sum"><joint joint="a" coef="1"/><joint joint="b" coef="1"/></fixed></tendon>
  <actuator><motor name="push" joint="a"/></actuator>
</mujoco>)");
  const simloop::Scenario s = simloop::Scenario::from_toml_string(
      "steps = 50\n[[control]]\nactuator = \"push\"\nvalue = 1.0\n[reset]\nqvel = [0.0, 0.5]\n"
      "[record]\njoints = \"all\"\ntendons = [\"sum\"]\n");
  const simloop::RunRecord r = simloop::run_scenario(scene, s, {});
  std::vector<std::string> names;
  for (const simloop::Column& c : r.columns) names.push_back(c.name);
  EXPECT_EQ(names, (std::vector<std::string>{"step", "time", "push_ctrl", "a_pos", "a_vel", "b_pos", "b_vel",
                                             "sum_length", "sum_vel", "contacts"}));
  for (std::int64_t row = 0; row < r.trajectory.rows(); ++row) {
    EXPECT_EQ(r.trajectory.at(row, 7), r.trajectory.at(row, 3) + r.trajectory.at(row, 5)) << row;
    EXPECT_EQ(r.trajectory.at(row, 8), r.trajectory.at(row, 4) + r.trajectory.at(row, 6)) << row;
  }
  EXPECT_GT(r.trajectory.at(50, 7), 0.05);  // the slides moved
  EXPECT_EQ(test::error_of([&] {
              (void)simloop::run_scenario(scene,
                                          simloop::Scenario::from_toml_string("[record]\ntendons = [\"summ\"]\n"), {});
            }),
            "record.tendons: no tendon named 'summ' (did you mean 'sum'?); the scene's tendons: sum");
}

namespace {

int column_of(const std::vector<simloop::Column>& columns, const std::string& name) {
  const auto at =
      std::find_if(columns.begin(), columns.end(), [&](const simloop::Column& c) { return c.name == name; });
  return at == columns.end() ? -1 : static_cast<int>(at - columns.begin());
}

bool equal_bits(const double* a, const double* b, std::size_t n) { return std::memcmp(a, b, n * sizeof(double)) == 0; }

}  // namespace

TEST(Recorder, ReadDataAtStepReadsMjDataAsTheLastStepOfAnEpisodeLeftIt) {
  // Gymnasium's moment: the reset's mj_forward (cfrc_ext 0), else the last mj_step, then mj_rnePostConstraint.
  const simloop::Scenario scenario = simloop::Scenario::from_toml_string(
      "scene = \"pusht.xml\"\n[record]\ndata = [[\"cfrc_ext\", \"tblock\"], [\"xpos\", \"tblock\"]]", "",
      SIMLOOP_TEST_SCENES);
  simloop::Episodes episodes(simloop::load_scene(scenario), scenario, simloop::ScenarioConfig{}, 1);
  episodes.read_data_at_step(true);
  const int force = column_of(episodes.columns(), "tblock_cfrc_ext0"),
            x = column_of(episodes.columns(), "tblock_xpos0");
  const mjModel* m = episodes.model().get();
  const int b = mj_name2id(m, mjOBJ_BODY, "tblock");
  simloop::Data by_hand(episodes.model());
  mj_forward(m, by_hand.get());
  std::vector<double> row(static_cast<std::size_t>(episodes.width())), action{0.8, 0.3};
  episodes.reset(0, 0, row.data());
  EXPECT_EQ(std::count(row.data() + force, row.data() + force + 6, 0.0), 6);
  EXPECT_TRUE(equal_bits(row.data() + x, by_hand.get()->xpos + 3 * b, 3));
  std::uint8_t terminated = 0, truncated = 0;
  for (int k = 0; k < 40; ++k) {
    episodes.step(action.data(), 2, 5, nullptr, 0, row.data(), &terminated, &truncated);
    std::copy(action.begin(), action.end(), by_hand.get()->ctrl);
    for (int i = 0; i < 5; ++i) mj_step(m, by_hand.get());
    mj_rnePostConstraint(m, by_hand.get());
    EXPECT_TRUE(equal_bits(row.data() + force, by_hand.get()->cfrc_ext + 6 * b, 6)) << k;
    EXPECT_TRUE(equal_bits(row.data() + x, by_hand.get()->xpos + 3 * b, 3)) << k;
  }
  EXPECT_NE(row[static_cast<std::size_t>(force) + 5], 0.0);  // the floor carries the block
}
