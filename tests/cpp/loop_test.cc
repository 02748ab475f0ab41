// The observation before a decision (DecisionStep, loop.hpp): the first half
// of the next mj_step where it can be, a whole forward pass where not; either
// way the bits of a forward pass kept aside (forward_keeping_state) then
// mj_step, in the observation and in the run.
#include "loop.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "mujoco_compat.hpp"
#include "simloop/model.hpp"
#include "simloop/recorder.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/shove.hpp"
#include "simloop/state.hpp"

namespace {

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

std::string scene_text(const char* file) {
  std::ifstream in(std::string(SIMLOOP_TEST_SCENES) + "/" + file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The test PushT scene, its T-block's free joint named (to record its qpos)
// and push_y a servo, with each `from` in its text replaced by its `to`.
simloop::Model pusht(const std::vector<std::pair<std::string, std::string>>& changes = {}) {
  std::string xml = scene_text("pusht.xml");
  xml.replace(xml.find("<freejoint/>"), 12, "<freejoint name=\"tblock_free\"/>");
  // A position servo: its force follows the state, not only the ctrl.
  const std::string motor = "<motor name=\"push_y\" joint=\"slide_y\" gear=\"5\"";
  xml.replace(xml.find(motor), motor.size(), "<position name=\"push_y\" joint=\"slide_y\" kp=\"20\"");
  for (const auto& [from, to] : changes) {
    const std::size_t at = xml.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) xml.replace(at, from.size(), to);
  }
  return simloop::Model::from_xml_string(xml);
}

simloop::Model pusht_integrated_by(const std::string& integrator) {
  return pusht({{"<option timestep=\"0.002\"/>", "<option timestep=\"0.002\" integrator=\"" + integrator + "\"/>"}});
}

constexpr const char* kPushtRecord =
    "[[disturbance]]\nbody = \"tblock\"\nnewtons = [0.5, 1.5]\ndirection = [0, 1, 0]\nrandom_sign = true\n"
    "start_step = 60\nsteps = 40\n"
    "[record]\nbodies = [\"tblock\", \"pusher\"]\njoints = [\"tblock_free\", \"slide_x\"]\n"
    "actuators = [\"push_x\", \"push_y\"]\nsensors = [\"tblock_pos\", \"tip_x\"]\ncontacts = true\nncon = true\n";

// Takes `steps` steps with a decision every `every`, twice from the same
// start: observing through DecisionStep, and through forward_keeping_state
// then mj_step. Expects the same observations and end state bit for bit, and
// DecisionStep to have begun the next step at each decision iff `halfway`.
// `watch` sees the state at each decision.
void expect_the_same_run(const simloop::Model& scene, const std::string& scenario_toml, bool halfway,
                         std::int64_t steps = 300, std::int64_t every = 7,
                         const std::function<void(const mjData*)>& watch = nullptr) {
  const simloop::Scenario scenario = simloop::Scenario::from_toml_string(
      "name = \"t\"\nscene = \"pusht.xml\"\nsteps = " + std::to_string(steps) + "\n" + scenario_toml, "test",
      SIMLOOP_TEST_SCENES);
  const mjModel* m = scene.get();
  const simloop::ResolvedScenario resolved = simloop::resolve(scenario, m);
  const auto draws = simloop::make_draws(7);
  const simloop::Schedule schedule = simloop::build_schedule(resolved, scenario, m->opt.timestep, *draws);
  const simloop::Recorder recorder(m, resolved, schedule);
  simloop::Data data_a(scene), data_b(scene);
  mjData* a = data_a.get();
  mjData* b = data_b.get();
  simloop::ScheduledInputs inputs_a(schedule, false), inputs_b(schedule, false);
  mj_forward(m, a);
  mj_forward(m, b);
  simloop::detail::DecisionStep decision(m, recorder);
  const auto width = static_cast<std::size_t>(recorder.width());
  for (std::int64_t step = 0; step < steps; step += every) {
    std::vector<double> seen_a(width), seen_b(width);
    inputs_a.write(step, a);
    const int ncon_a = a->ncon;
    decision.observe(m, a);
    EXPECT_EQ(decision.begun(), halfway) << "step " << step;
    EXPECT_EQ(decision.entering_ncon(a), ncon_a) << "the count the step began with, step " << step;
    recorder.before_step(seen_a.data(), step, m, a, true, decision.entering_ncon(a));
    recorder.after_step(seen_a.data(), m, a);
    inputs_b.write(step, b);
    const int ncon_b = b->ncon;
    simloop::forward_keeping_state(m, b);
    recorder.before_step(seen_b.data(), step, m, b, true, ncon_b);
    recorder.after_step(seen_b.data(), m, b);
    ASSERT_TRUE(same_bits(seen_a, seen_b)) << "the observation at step " << step;
    if (watch) watch(a);
    for (int u = 0; u < m->nu; ++u) a->ctrl[u] = b->ctrl[u] = std::sin(0.05 * static_cast<double>(step) + u);
    for (std::int64_t s = step; s < std::min(steps, step + every); ++s) {
      inputs_a.write(s, a);
      decision.step(m, a);
      ASSERT_EQ(decision.entering_ncon(a), a->ncon) << "after a step, d's own count";
      inputs_b.write(s, b);
      mj_step(m, b);
    }
  }
  EXPECT_TRUE(same_bits(simloop::get_state(m, a), simloop::get_state(m, b))) << "the end state";
  EXPECT_GT(a->time, 0.0);
}

}  // namespace

TEST(DecisionStep, BeginsTheNextStepAndGivesTheBitsOfAWholeForwardPass) {
  // A free joint (2.2 normalises its quaternion in place: held aside),
  // actuator forces of the ctrl in force, contacts, a disturbance.
  expect_the_same_run(pusht(), kPushtRecord, true);
  expect_the_same_run(pusht(), kPushtRecord, true, 40, 1);
  expect_the_same_run(pusht_integrated_by("implicit"), kPushtRecord, true);
}

TEST(DecisionStep, TakesAWholeForwardPassForWhatTheFirstHalfCannotGive) {
  // RK4's mj_step is not mj_step1 + mj_step2.
  expect_the_same_run(pusht_integrated_by("RK4"), kPushtRecord, false);
  // An acceleration-stage sensor, recorded; unrecorded, it changes nothing.
  const simloop::Model imu = pusht({{"<geom name=\"t_bar\"", "<site name=\"imu\"/><geom name=\"t_bar\""},
                                    {"<sensor>", "<sensor>\n    <accelerometer name=\"imu_acc\" site=\"imu\"/>"}});
  std::string record = kPushtRecord;
  record.replace(record.find("\"tip_x\"]"), 8, "\"tip_x\", \"imu_acc\"]");
  expect_the_same_run(imu, record, false);
  expect_the_same_run(imu, kPushtRecord, true);
}

TEST(DecisionStep, LeavesABadStateAndACallbackToTheWholeStep) {
  const simloop::Model scene = pusht();
  const mjModel* m = scene.get();
  const simloop::Scenario scenario = simloop::Scenario::from_toml_string(
      "name = \"t\"\nscene = \"pusht.xml\"\nsteps = 10\n[record]\njoints = [\"slide_x\"]\n", "test",
      SIMLOOP_TEST_SCENES);
  const simloop::ResolvedScenario resolved = simloop::resolve(scenario, m);
  const auto draws = simloop::make_draws(0);
  const simloop::Recorder recorder(m, resolved, simloop::build_schedule(resolved, scenario, m->opt.timestep, *draws));
  simloop::Data data(scene);
  mjData* d = data.get();
  // Stepped inside simloop's guard, as the library steps it: a warning
  // raised outside simloop's calls would go to MuJoCo's own handler (and
  // MUJOCO_LOG.TXT).
  const auto guarded = [](auto&& f) { simloop::detail::mujoco_call(f); };
  guarded([&] { mj_forward(m, d); });
  simloop::detail::DecisionStep decision(m, recorder);
  guarded([&] { decision.observe(m, d); });
  EXPECT_TRUE(decision.begun());
  // A callback would see the ctrl before the decision. What it warns, the
  // step counts once (the whole forward pass and the step both run it).
  mjcb_passive = [](const mjModel*, mjData* data) { mj_warning(data, mjWARN_CONTACTFULL, 1); };
  d->warning[mjWARN_CONTACTFULL].number = 0;
  guarded([&] { decision.observe(m, d); });
  EXPECT_FALSE(decision.begun());
  guarded([&] { decision.step(m, d); });
  mjcb_passive = nullptr;
  EXPECT_EQ(d->warning[mjWARN_CONTACTFULL].number, 1) << "the callback's warning, counted once, as mj_step alone";
  // mj_step1 would reset a bad velocity at the observation: mj_step resets it
  // at the step, as without a decision.
  d->qvel[0] = std::numeric_limits<double>::quiet_NaN();
  guarded([&] { decision.observe(m, d); });
  EXPECT_FALSE(decision.begun());
  EXPECT_TRUE(std::isnan(d->qvel[0]));
  guarded([&] { decision.step(m, d); });
  EXPECT_EQ(d->warning[mjWARN_BADQVEL].number, 1) << "counted once, by the step, as mj_step alone counts it";
  EXPECT_FALSE(std::isnan(d->qvel[0]));
  guarded([&] { decision.observe(m, d); });
  EXPECT_TRUE(decision.begun());
}

#if mjVERSION_HEADER >= 300
TEST(DecisionStep, TakesAWholeForwardPassWithPlugins) {
  // An actuator plugin computes in mj_fwdActuation: the observation's extra
  // call must not be the one that counts.
  std::string xml = scene_text("plugin_pid.xml");
  xml.replace(xml.find("<config key=\"kd\""), 0, "<config key=\"ki\" value=\"10\"/>\n        ");
  xml.replace(xml.find("joint=\"hinge\"/>"), 0, "actdim=\"1\" ");  // (its integral is an activation)
  expect_the_same_run(simloop::Model::from_xml_string(xml), "[record]\njoints = [\"hinge\"]\nactuators = [\"hold\"]\n",
                      false, 200, 5);
}
#endif

#if mjVERSION_HEADER >= 340
TEST(DecisionStep, FollowsTreesThatFallAsleep) {
  const simloop::Model scene = simloop::Model::from_file(std::string(SIMLOOP_TEST_SCENES) + "/sleeping_boxes.xml");
  int asleep = 0;  // decisions with a tree asleep
  expect_the_same_run(scene,
                      "[[disturbance]]\nbody = \"b\"\nnewtons = [3, 3]\ndirection = [1, 0, 0]\nstart_step = 700\n"
                      "steps = 20\n[record]\nbodies = [\"a\", \"b\", \"c\"]\ncontacts = true\n",
                      true, 1500, 50, [&](const mjData* d) { asleep += d->ntree_awake < scene.get()->ntree; });
  EXPECT_GT(asleep, 0);
}
#endif

// A row holds one state: under RK4 too, whose later stages would leave the
// poses of another (its last stage's) for a read after the step.
TEST(Loop, EveryColumnOfARowIsOfTheRowsStateUnderEveryIntegrator) {
  const simloop::Scenario scenario =
      simloop::Scenario::from_toml_string(std::string("name = \"t\"\nscene = \"pusht.xml\"\nsteps = 200\n") +
                                              kPushtRecord + "[reset]\nqvel = [0.5, 0.3, 0, 0, 0, 2, 0, 0]\n",
                                          "test", SIMLOOP_TEST_SCENES);
  for (const char* integrator : {"Euler", "implicit", "RK4"}) {
    const simloop::RunRecord r = simloop::run_scenario(pusht_integrated_by(integrator), scenario, {});
    const auto column = [&](const std::string& name) {
      for (std::size_t c = 0; c < r.columns.size(); ++c) {
        if (r.columns[c].name == name) return static_cast<std::int64_t>(c);
      }
      ADD_FAILURE() << "no column " << name;
      return std::int64_t{0};
    };
    double moved = 0.0;
    for (const auto& [body, joint] :
         {std::pair{"tblock_x", "tblock_free_pos0"}, std::pair{"tblock_y", "tblock_free_pos1"},
          std::pair{"tblock_z", "tblock_free_pos2"}}) {
      const std::int64_t b = column(body), j = column(joint);
      for (std::int64_t row = 0; row < r.trajectory.rows(); ++row) {
        // A free joint's body sits at its qpos: bit for bit, when both are of one state.
        ASSERT_EQ(r.trajectory.at(row, b), r.trajectory.at(row, j)) << integrator << " " << body << " row " << row;
        moved = std::max(moved, std::abs(r.trajectory.at(row, j) - r.trajectory.at(0, j)));
      }
    }
    EXPECT_GT(moved, 1e-3) << integrator << ": the block moves, so a lag would show";
  }
}
