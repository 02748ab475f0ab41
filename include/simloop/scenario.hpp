// A scenario: the chapter's loop for any scene, as data.
//
// The chapter's loop is "write intent into ctrl, write interference into
// xfrc_applied, mj_step, look at what changed". A Scenario says what to write
// and what to look at: the scene, the timestep, the length, the controls
// (intent), the disturbances (interference) and what is recorded. The life of
// a run is then the shape MuJoCo's testspeed sample has:
//
//   Scenario (data: a TOML file, Python keywords, or Scenario::chapter())
//     -> resolve() against the compiled model: names become indices, once,
//        with errors that list what the scene has
//     -> build_schedule() from the run's one seed: every input of every step,
//        decided before the first step (the only randomness is drawn here)
//     -> the loop, which only reads the schedule
//     -> recorders, which write what was asked.
//
// This header holds the first three; they depend on nothing but the model.
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "simloop/model.hpp"
#include "simloop/scene_params.hpp"
#include "simloop/shove.hpp"

namespace simloop {

// The chapter's run as a scenario is named so (Scenario::chapter(), and the
// record of the chapter's own run).
inline constexpr std::string_view kChapterScenarioName = "ch0.1-sim-loop";

// A point or span of a run, in steps or in simulated seconds (converted with
// the run's timestep, rounded to the nearest step).
struct When {
  enum class Unit { kSteps, kSeconds, kFractionOfRun };
  double value = 0.0;
  Unit unit = Unit::kSteps;
  std::int64_t count = 0;  // kSteps: the exact number (value, a double, rounds it above 2^53)

  [[nodiscard]] static When steps(std::int64_t n) { return {static_cast<double>(n), Unit::kSteps, n}; }
  [[nodiscard]] static When seconds(double s) { return {s, Unit::kSeconds, 0}; }
  // A fraction of the run's length: the chapter shoves at steps // 2 (0.5).
  [[nodiscard]] static When fraction(double f) { return {f, Unit::kFractionOfRun, 0}; }
  // The step this names in a run of `run_steps` steps of `timestep` seconds.
  [[nodiscard]] std::int64_t to_steps(double timestep, std::int64_t run_steps) const;
};

// Intent: what one actuator's ctrl holds over the run.
struct ControlSpec {
  std::string actuator;  // a name, or an index written as a number ("0")
  // Piecewise constant: each (from, value) holds from `from` until the next.
  // A constant is one entry from step 0. Before the first entry the ctrl is 0.
  std::vector<std::pair<When, double>> schedule;
  // The CSV file the schedule was read from (a file's `csv`, resolved), or empty: what a cache of the scenario
  // must check is unchanged.
  std::filesystem::path csv;
};

// Interference: a force and/or torque on one body, in the world frame, over
// a window of steps, written into xfrc_applied (and an explicit zero after).
struct DisturbanceSpec {
  std::string body;
  std::array<double, 3> force{};   // N, world frame, at the body's centre of mass
  std::array<double, 3> torque{};  // N m, world frame
  // Drawn from the run's generator when set: the force becomes
  // direction * uniform(newtons[0], newtons[1]), times a random sign if
  // random_sign. The chapter's shove: [6, 12] N along +y, random sign.
  std::optional<std::array<double, 2>> newtons;
  bool random_sign = false;
  When start = When::steps(0);
  When duration = When::steps(1);
};

// What the trajectory records, by name. Empty lists mean the defaults: every
// body on a free joint, every actuator.
struct RecordSpec {
  std::vector<std::string> bodies;     // position, orientation, linear and angular velocity
  std::vector<std::string> joints;     // position, velocity (the joint's qpos/qvel)
  std::vector<std::string> actuators;  // ctrl as applied (after ctrlrange clamping), force
  std::vector<std::string> sensors;    // sensordata
  std::vector<std::string> tendons;    // length, rate of change
  // Any of mjData's arrays of numbers by object, as MuJoCo derives it for
  // the row's state: [array, object] ("cfrc_ext", "torso"; "site_xpos",
  // "tip"; "sensordata", a sensor; "qfrc_actuator", a joint).
  std::vector<std::pair<std::string, std::string>> data;
  // Contact forces between two bodies or geoms, by name: [a, b], the force
  // b gets from a, summed over their contacts (mj_contactForce), world frame.
  std::vector<std::pair<std::string, std::string>> contact_forces;
  bool contacts = true;  // `contacts`: the contacts of each row's state
  bool ncon = false;     // `ncon`: the contacts when its step began (the chapter's)
  // "all" in a scenario file instead of a list: every one the scene has, by
  // index (every body that can move), after any named above.
  bool all_bodies = false, all_joints = false, all_actuators = false, all_sensors = false, all_tendons = false;
};

// How a run starts, beyond the scene's reset pose: a scenario file's
// [reset] table, or one episode's reset options (Episodes::reset). What is
// random is drawn from the run's generator after the disturbances, in this
// order: each param's value, then the noise on each qpos coordinate (0 to
// nq - 1, one draw each when any of its widths is not zero), then on each
// qvel coordinate the same way, then each goal's x, y, z. Sizes and names
// are checked when resolved.
struct ResetSpec {
  std::vector<double> qpos;  // the scene's nq values, or empty: its qpos0
  std::vector<double> qvel;  // nv values, or empty: at rest
  // Noise on qpos or qvel: a width for every coordinate (`scale`), or one
  // per coordinate (`each`, nq or nv values), or per joint by name (its
  // coordinates; the others none). uniform: plus uniform(-w, +w); normal:
  // plus w * standard_normal(draws) (draw order: standard_normal, shove.hpp).
  // A coordinate of width 0 is drawn for but left exact. Quaternions are
  // renormalised when qpos is set.
  struct Noise {
    enum class Distribution { kUniform, kNormal };
    double scale = 0.0;
    std::vector<double> each;
    std::vector<std::pair<std::string, double>> joints;
    Distribution distribution = Distribution::kUniform;
  };
  Noise qpos_noise;
  Noise qvel_noise;
  // A scene parameter (scene_params.hpp) for this run only, uniform in [low, high].
  // A float array's draw is rounded to float: the value shown is the one run.
  struct Param {
    SceneParam::Kind kind = SceneParam::Kind::kFriction;
    std::string name;
    double low = 0.0, high = 0.0;
    std::string field;  // a model value's array and index (SceneParam::Kind::kModel)
    int index = 0;
  };
  std::vector<Param> params;
  // A keyframe of the scene by name: the start (qpos, qvel, act, ctrl,
  // mocap_pos and mocap_quat, as mj_resetDataKeyframe sets them) that qpos,
  // qvel, noise and goals then apply over. Empty: the scene's reset pose.
  std::string keyframe;
  // A goal: a mocap body's position for this run, each coordinate uniform in
  // [low, high] (low == high: fixed), drawn after the noise, x then y then z.
  struct Goal {
    std::string body;
    std::array<double, 3> low{}, high{};
  };
  std::vector<Goal> goals;
};

struct Scenario {
  std::string name;                // for titles and recording ids; the file's stem by default
  std::filesystem::path scene;     // an MJCF file; empty: the chapter's embedded scene
  std::optional<double> timestep;  // the scene's own unless given
  When length = When::steps(2000);
  std::vector<ControlSpec> controls;
  std::vector<DisturbanceSpec> disturbances;
  RecordSpec record;
  ResetSpec reset;

  // The chapter's run: its scene, ctrl 1.0 on push_motor, the shove on box;
  // it records the box, the pusher's joint and ncon, as the chapter does.
  [[nodiscard]] static Scenario chapter();
  // A scenario file (TOML). Relative `scene` paths resolve against the
  // file's folder. Throws InvalidArgument naming the file, the key and what
  // is wrong; IoError if it cannot be read.
  [[nodiscard]] static Scenario from_toml_file(const std::filesystem::path& path);
  // The same from text; `source` names it in errors, `base` resolves `scene`,
  // and a text without `name` gets `default_name` (a file's: its stem).
  [[nodiscard]] static Scenario from_toml_string(std::string_view text, std::string_view source = "<string>",
                                                 const std::filesystem::path& base = {},
                                                 std::string_view default_name = {});
};

// A scenario's names turned into the model's indices, checked once.
struct ResolvedScenario {
  struct Control {
    int actuator = -1;
    std::vector<std::pair<When, double>> schedule;
  };
  struct Disturbance {
    int body = -1;
    DisturbanceSpec spec;
  };
  std::vector<Control> controls;
  std::vector<Disturbance> disturbances;
  std::vector<int> bodies, joints, actuators, sensors, tendons;  // to record
  // A RecordSpec::data entry: values first .. first + count - 1 of mjData's
  // array `array` (the row of object `id` of `type`), its columns named from it.
  struct DataValues {
    std::string array;
    mjtObj type = mjOBJ_UNKNOWN;
    int id = -1;
    long long first = 0;
    int count = 0;
  };
  std::vector<DataValues> data;
  // A RecordSpec::contact_forces pair: each side a geom, or a body (its geoms).
  struct ContactPair {
    mjtObj type_a = mjOBJ_GEOM, type_b = mjOBJ_GEOM;
    int a = -1, b = -1;
    std::string name;  // its columns' stem: "<a>_<b>"
    // The force b gets from a over d's contacts between them, world frame
    // (N): each contact's force acts on its geom2 (mj_contactForce, in the
    // contact's frame). Calls MuJoCo unguarded: inside MuJoCo's error guard.
    void force(const mjModel* m, const mjData* d, double out[3]) const noexcept;
  };
  std::vector<ContactPair> contact_pairs;
  bool contacts = true, ncon = false;
  // What the start draws against: the scene's qpos0 and its nv, and where
  // each joint's coordinates are (noise by joint name).
  std::vector<double> qpos0;
  int nv = 0;
  struct JointCoordinates {
    std::string name;
    int qpos_first = 0, qpos_count = 0, dof_first = 0, dof_count = 0;
  };
  std::vector<JointCoordinates> joint_coordinates;
  // The scene's keyframes by name (a keyframe's qpos and qvel: what noise
  // draws about), and its mocap bodies by name with their mocap index.
  std::vector<std::string> keyframes;
  std::vector<double> key_qpos, key_qvel;
  std::vector<std::pair<std::string, int>> mocap_bodies;
};

// Resolves every name in `scenario` against `model`, and checks its reset
// (check_reset). An unknown name throws InvalidArgument: "no body named
// 'tblok' (did you mean 'tblock'?); bodies that can move: tblock, pusher".
// Actuators may be given by index.
[[nodiscard]] ResolvedScenario resolve(const Scenario& scenario, const mjModel* model);

// Every input of a run, decided up front. The loop only reads it.
struct Schedule {
  std::int64_t steps = 0;
  struct ControlChange {
    std::int64_t step = 0;  // from this step on...
    int actuator = -1;      // ...ctrl[actuator] holds...
    double value = 0.0;     // ...this (as written; MuJoCo clamps to ctrlrange)
  };
  std::vector<ControlChange> control_changes;  // sorted by step (stable)
  struct Force {
    int body = -1;
    std::array<double, 6> wrench{};  // force, torque: what xfrc_applied gets
    std::int64_t start = 0;          // first step it acts
    std::int64_t end = 0;            // first step it no longer acts (start <= end <= steps)
    std::int64_t asked_end = 0;      // where the scenario asked it to end (may be past the run)
  };
  std::vector<Force> forces;
  // How the run starts (the scenario's ResetSpec, drawn): qpos and qvel to
  // set after the reset (empty: the scene's own; its quaternions are made
  // unit when set, mj_normalizeQuat), and the scene parameters
  // of this run's own copy of the model (empty: the shared model).
  struct Start {
    std::vector<double> qpos, qvel;
    std::vector<SceneParam> params;
    int keyframe = -1;  // the keyframe reset to first, or -1: the scene's reset pose
    struct MocapPos {
      int mocap = -1;    // the mocap index (body_mocapid)
      std::string body;  // its body's name, for the columns that show it (drawn_columns)
      std::array<double, 3> pos{};
    };
    std::vector<MocapPos> goals;  // written into mocap_pos after the reset
  };
  Start start;
};

// Draws the random disturbances (in scenario order), then the start
// (spec.reset), and lays out the inputs for a run of the scenario's length
// at `timestep`.
[[nodiscard]] Schedule build_schedule(const ResolvedScenario& scenario, const Scenario& spec, double timestep,
                                      Draws& draws);

// What a start drew, as columns (a batch table's, an env's info): each
// scene parameter's value under tables.py's param_column name (friction,
// friction_<geom>, mass_<body>, ...), then each goal's goal_<body>_x, _y, _z.
// Empty for a start that draws none, so such runs' tables keep their columns.
[[nodiscard]] std::vector<std::pair<std::string, double>> drawn_columns(const Schedule::Start& start);

// One episode's reset options over the scenario's own start: `text` is a
// scenario file's text holding a [reset] table; each key that table names
// (qpos, qvel, qpos_noise, qvel_noise, their _distribution, keyframe, goal and param: the whole lists, `param = []`
// for none) replaces own's, and the keys it leaves out keep own's. Throws
// InvalidArgument naming `source` as from_toml_string does.
[[nodiscard]] ResetSpec reset_over(const ResetSpec& own, std::string_view text, std::string_view source);

// Checks a ResetSpec against the resolved scene: qpos of nq values, qvel of
// nv, every value finite, noise widths finite and >= 0 (nq or nv of them,
// joints the scene has), each param's low <= high and its name and values
// valid for the scene (InvalidArgument naming the key: "reset.qpos must hold
// the scene's nq = 7 values, got 3").
void check_reset(const ResolvedScenario& scenario, const ResetSpec& reset, const mjModel* m);

// A noise's width on each qpos (of_qpos) or qvel coordinate of the scene.
[[nodiscard]] std::vector<double> noise_widths(const ResolvedScenario& scenario, const ResetSpec::Noise& noise,
                                               bool of_qpos);

}  // namespace simloop
