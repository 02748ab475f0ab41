// The stepping core (stepper.hpp) and the loop on it (loop.hpp). The
// observation before a decision (Stepper::observe): the first half of the
// next mj_step where it can be, a whole forward pass where not; either way
// the bits of a forward pass kept aside (forward_keeping_state) then
// mj_step, in the observation and in the run.
#include "loop.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "mujoco_compat.hpp"
#include "simloop/episode.hpp"
#include "simloop/model.hpp"
#include "simloop/recorder.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/shove.hpp"
#include "simloop/sim.hpp"
#include "simloop/state.hpp"
#include "stepper.hpp"

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

// The scheduled inputs, written before each step the core takes.
struct WriteInputs : simloop::detail::StepHooks {
  simloop::ScheduledInputs& inputs;
  explicit WriteInputs(simloop::ScheduledInputs& to_write) : inputs(to_write) {}
  void before_step(std::int64_t step, mjData* d) noexcept { inputs.write(step, d); }
};

// Takes `steps` steps with a decision every `every`, twice from the same
// start: observing through the core, and through forward_keeping_state then
// mj_step. Expects the same observations and end state bit for bit, and the
// core to have begun the next step at each decision iff `halfway`. `watch`
// sees the state at each decision.
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
  simloop::detail::Stepper core(m, recorder.reads_acceleration_stage());
  core.reset(m, a, {});
  mj_forward(m, b);
  const auto width = static_cast<std::size_t>(recorder.width());
  for (std::int64_t step = 0; step < steps; step += every) {
    std::vector<double> seen_a(width), seen_b(width);
    inputs_a.write(step, a);
    const int ncon_a = a->ncon;
    core.observe(m, a, step);
    EXPECT_EQ(core.begun(), halfway) << "step " << step;
    EXPECT_EQ(core.entering_ncon(a), ncon_a) << "the count the step began with, step " << step;
    recorder.before_step(seen_a.data(), step, m, a, true, core.entering_ncon(a));
    recorder.after_step(seen_a.data(), m, a);
    inputs_b.write(step, b);
    const int ncon_b = b->ncon;
    simloop::forward_keeping_state(m, b);
    recorder.before_step(seen_b.data(), step, m, b, true, ncon_b);
    recorder.after_step(seen_b.data(), m, b);
    ASSERT_TRUE(same_bits(seen_a, seen_b)) << "the observation at step " << step;
    if (watch) watch(a);
    for (int u = 0; u < m->nu; ++u) a->ctrl[u] = b->ctrl[u] = std::sin(0.05 * static_cast<double>(step) + u);
    std::int64_t taken = step;
    core.run(m, a, taken, std::min(steps, step + every), WriteInputs(inputs_a), nullptr);
    EXPECT_EQ(taken, std::min(steps, step + every));
    EXPECT_EQ(core.entering_ncon(a), a->ncon) << "after a step, d's own count";
    for (std::int64_t s = step; s < std::min(steps, step + every); ++s) {
      inputs_b.write(s, b);
      mj_step(m, b);
    }
  }
  EXPECT_TRUE(same_bits(simloop::get_state(m, a), simloop::get_state(m, b))) << "the end state";
  EXPECT_GT(a->time, 0.0);
}

}  // namespace

TEST(Decision, BeginsTheNextStepAndGivesTheBitsOfAWholeForwardPass) {
  // A free joint (2.2 normalises its quaternion in place: held aside),
  // actuator forces of the ctrl in force, contacts, a disturbance.
  expect_the_same_run(pusht(), kPushtRecord, true);
  expect_the_same_run(pusht(), kPushtRecord, true, 40, 1);
  expect_the_same_run(pusht_integrated_by("implicit"), kPushtRecord, true);
}

TEST(Decision, TakesAWholeForwardPassForWhatTheFirstHalfCannotGive) {
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

TEST(Decision, LeavesABadStateAndACallbackToTheWholeStep) {
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
  simloop::detail::Stepper core(m, recorder.reads_acceleration_stage());
  core.reset(m, d, {});
  const auto counted = [&](const std::string& name) {
    for (const simloop::Warning& w : core.health().warnings()) {
      if (w.name == name) return w.count;
    }
    return std::int64_t{0};
  };
  std::int64_t step = 0;
  core.observe(m, d, step);
  EXPECT_TRUE(core.begun());
  // A callback would see the ctrl before the decision. What it warns, the
  // step counts once (the whole forward pass and the step both run it).
  mjcb_passive = [](const mjModel*, mjData* data) { mj_warning(data, mjWARN_CONTACTFULL, 1); };
  d->warning[mjWARN_CONTACTFULL].number = 0;
  core.observe(m, d, step);
  EXPECT_FALSE(core.begun());
  core.run(m, d, step, step + 1, simloop::detail::StepHooks{}, nullptr);
  mjcb_passive = nullptr;
  EXPECT_EQ(counted("mjWARN_CONTACTFULL"), 1) << "the callback's warning, counted once, as mj_step alone";
  EXPECT_FALSE(core.health().broken());
  // mj_step1 would reset a bad velocity at the observation: mj_step resets it
  // at the step, as without a decision.
  d->qvel[0] = std::numeric_limits<double>::quiet_NaN();
  core.observe(m, d, step);
  EXPECT_FALSE(core.begun());
  EXPECT_TRUE(std::isnan(d->qvel[0]));
  core.run(m, d, step, step + 1, simloop::detail::StepHooks{}, nullptr);
  EXPECT_EQ(counted("mjWARN_BADQVEL"), 1) << "counted once, by the step, as mj_step alone counts it";
  EXPECT_TRUE(core.health().broken()) << "MuJoCo reset the state";
  EXPECT_FALSE(std::isnan(d->qvel[0]));
  core.observe(m, d, step);
  EXPECT_TRUE(core.begun());
}

#if mjVERSION_HEADER >= 300
TEST(Decision, TakesAWholeForwardPassWithPlugins) {
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
TEST(Decision, FollowsTreesThatFallAsleep) {
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

// The run's inputs written through a Sim, step by step up to `end`: the
// motor on, each scheduled force on at its start and off at its end.
void step_as_scheduled(simloop::Sim& sim, const simloop::Schedule& schedule, std::int64_t end) {
  sim.set_ctrl(1.0);
  for (std::int64_t step = sim.steps_taken(); step < end; ++step) {
    for (const simloop::Schedule::Force& f : schedule.forces) {
      const std::array<double, 3> force{f.wrench[0], f.wrench[1], f.wrench[2]}, none{};
      if (step == f.start) sim.apply_wrench(f.body, &force, nullptr);
      if (step == f.end) sim.apply_wrench(f.body, &none, nullptr);
    }
    sim.step();
  }
}

bool same_warnings(const std::vector<simloop::Warning>& a, const std::vector<simloop::Warning>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].name != b[i].name || a[i].count != b[i].count || a[i].first_step != b[i].first_step ||
        a[i].message != b[i].message) {
      return false;
    }
  }
  return true;
}

// One core steps them all: the same inputs through a run, a Sim and an
// episode give the same state and the same warnings. The chapter's scene at
// 0.3 s a step: the shove sends the box through the floor mid-run.
TEST(Stepper, ARunASimAndAnEpisodeStepTheSameBitsAndWarnTheSame) {
  const simloop::Scenario chapter = simloop::Scenario::chapter();
  const simloop::Model scene = simloop::load_scene(chapter);
  simloop::ScenarioConfig config;
  config.timestep = 0.3;
  const simloop::RunRecord run = simloop::run_scenario(scene, chapter, config);
  ASSERT_FALSE(run.warnings.empty());
  const simloop::Warning& diverged = run.warnings.back();
  ASSERT_EQ(diverged.name, "simloop_DIVERGED");
  ASSERT_GT(diverged.first_step, 0);
  ASSERT_GT(diverged.count, 1);

  simloop::Sim sim(scene.with_timestep(0.3));
  step_as_scheduled(sim, run.schedule, run.schedule.steps);
  EXPECT_TRUE(same_bits(sim.state(), run.final_state));
  EXPECT_TRUE(same_warnings(sim.warnings(), run.warnings));

  // The episode ends after the step that diverged: so does a Sim.
  simloop::Episodes episodes(scene, chapter, config, 1);
  std::vector<double> observation(static_cast<std::size_t>(episodes.width()));
  episodes.reset(0, config.seed, observation.data());
  const double action = 1.0;
  std::uint8_t terminated = 0, truncated = 0;
  while (!terminated && !truncated) {
    episodes.step(&action, 1, 10, nullptr, 0, observation.data(), &terminated, &truncated);
  }
  ASSERT_EQ(terminated, 1);
  ASSERT_EQ(episodes.steps_taken(0), diverged.first_step + 1);
  simloop::Sim until_diverged(scene.with_timestep(0.3));
  step_as_scheduled(until_diverged, run.schedule, episodes.steps_taken(0));
  EXPECT_TRUE(same_bits(until_diverged.state(), simloop::get_state(episodes.model(0).get(), episodes.data(0))));
  EXPECT_TRUE(same_warnings(until_diverged.warnings(), episodes.warnings(0)));
}
