// Scenarios as data and their schedules: When, Scenario::chapter() and
// build_schedule (every input of a run, drawn up front), and reading a
// scenario file (its TOML is parsed in scenario_toml.cc, names resolved in
// scenario_resolve.cc).
#include "simloop/scenario.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "model_detail.hpp"
#include "simloop/errors.hpp"
#include "simloop/fields.hpp"
#include "simloop/number_format.hpp"
#include "simloop/run.hpp"
#include "text_input.hpp"

namespace simloop {
namespace {

constexpr double kChapterTimestep = 0.002;

}  // namespace

std::int64_t When::to_steps(double timestep, std::int64_t run_steps) const {
  // Beyond any run a scenario can ask for; keeps the conversion defined.
  constexpr double kFar = 0x1p62;
  if (unit == Unit::kSteps) return std::clamp<std::int64_t>(count, 0, static_cast<std::int64_t>(kFar));
  const double steps =
      unit == Unit::kSeconds ? std::nearbyint(value / timestep) : std::floor(value * static_cast<double>(run_steps));
  return static_cast<std::int64_t>(std::clamp(steps, 0.0, kFar));
}

Scenario Scenario::from_toml_file(const std::filesystem::path& path) {
  const std::string toml = detail::read_text_file(path, detail::kMaxScenarioBytes, "a scenario file");
  if (detail::first_visible(toml) == '<') {
    throw InvalidArgument(path.string() +
                          ": an MJCF scene, not a scenario file (TOML): make it a scenario's scene "
                          "(scene = \"...\" in a scenario file, or simloop.Scenario(scene=...))");
  }
  return from_toml_string(toml, path.string(), path.parent_path(), path.stem().string());
}

Scenario Scenario::chapter() {
  Scenario s;
  s.name = std::string(kChapterScenarioName);
  s.timestep = kChapterTimestep;
  s.length = When::steps(2000);
  s.controls.push_back({"push_motor", {{When::steps(0), 1.0}}, {}});
  DisturbanceSpec shove;
  shove.body = "box";
  shove.force = {0.0, 1.0, 0.0};
  shove.newtons = std::array<double, 2>{6.0, 12.0};
  shove.random_sign = true;
  shove.start = When::fraction(0.5);
  shove.duration = When::steps(50);
  s.disturbances.push_back(shove);
  s.record.bodies = {"box"};
  s.record.joints = {"pusher_slide"};
  s.record.contacts = false;  // its contact count is the chapter's ncon
  s.record.ncon = true;
  return s;
}

Schedule build_schedule(const ResolvedScenario& scenario, const Scenario& spec, double timestep, Draws& draws) {
  check_positive_seconds("timestep", timestep);
  // A count of steps, worded as the chapter's run words it.
  if (spec.length.unit == When::Unit::kSteps) check_count("steps", spec.length.count, kMaxSteps);
  Schedule s;
  s.steps = spec.length.to_steps(timestep, 0);
  if (s.steps < 1) {
    throw InvalidArgument("the run's length (" + python_float_repr(spec.length.value) +
                          (spec.length.unit == When::Unit::kSeconds ? " s" : " steps") + ") is less than one step of " +
                          python_float_repr(timestep) + " s");
  }
  if (s.steps > kMaxSteps) {
    throw InvalidArgument("the run's length (" + python_float_repr(spec.length.value) +
                          (spec.length.unit == When::Unit::kSeconds ? " s" : " steps") + ") is more than " +
                          std::to_string(kMaxSteps) + " steps of " + python_float_repr(timestep) + " s");
  }
  for (const ResolvedScenario::Control& c : scenario.controls) {
    for (const auto& [when, value] : c.schedule) {
      const std::int64_t step = std::clamp<std::int64_t>(when.to_steps(timestep, s.steps), 0, s.steps);
      if (step < s.steps) s.control_changes.push_back({step, c.actuator, value});
    }
  }
  std::stable_sort(s.control_changes.begin(), s.control_changes.end(),
                   [](const Schedule::ControlChange& a, const Schedule::ControlChange& b) { return a.step < b.step; });
  // The only randomness: drawn here, in scenario order, before any step.
  for (const ResolvedScenario::Disturbance& d : scenario.disturbances) {
    const DisturbanceSpec& spec_d = d.spec;
    Schedule::Force f;
    f.body = d.body;
    double scale = 1.0;
    if (spec_d.newtons) {
      scale = draws.uniform((*spec_d.newtons)[0], (*spec_d.newtons)[1]);
      if (spec_d.random_sign) scale *= draws.sign();
    }
    for (int i = 0; i < 3; ++i) {
      // + 0.0: a negative scale times a zero component is -0.0, which would
      // print as "-0.0" where the chapter writes 0.
      f.wrench[static_cast<size_t>(i)] = scale * spec_d.force[static_cast<size_t>(i)] + 0.0;
      f.wrench[static_cast<size_t>(i + 3)] = spec_d.torque[static_cast<size_t>(i)];
    }
    f.start = std::clamp<std::int64_t>(spec_d.start.to_steps(timestep, s.steps), 0, s.steps);
    // A push shorter than half a step still pushes, for one step: rounded to
    // none it would vanish at a coarse timestep, while the report said it ran.
    const std::int64_t duration = std::max<std::int64_t>(1, spec_d.duration.to_steps(timestep, s.steps));
    f.asked_end = f.start + duration;
    f.end = std::min(f.asked_end, s.steps);
    s.forces.push_back(f);
  }
  // How the run starts, drawn after the disturbances: adding a [reset]
  // changes no disturbance's draw.
  const ResetSpec& reset = spec.reset;
  for (const ResetSpec::Param& p : reset.params) {
    double value = draws.uniform(p.low, p.high);  // [low, low]: exactly low
    if (p.kind == SceneParam::Kind::kModel && model_field_layout(p.field).element == Element::kFloat32) {
      value = static_cast<float>(value);
    }
    s.start.params.push_back({p.kind, p.name, value, p.field, p.index});
  }
  const auto start_at = [&](std::vector<double>& out, const std::vector<double>& given, std::vector<double> base,
                            const ResetSpec::Noise& noise, bool of_qpos) {
    const std::vector<double> widths = noise_widths(scenario, noise, of_qpos);
    const bool noisy = std::any_of(widths.begin(), widths.end(), [](double w) { return w != 0.0; });
    if (given.empty() && !noisy) return;
    out = given.empty() ? std::move(base) : given;
    if (!noisy) return;
    const bool normal = noise.distribution == ResetSpec::Noise::Distribution::kNormal;
    for (std::size_t i = 0; i < out.size(); ++i) {
      const double w = widths[i];
      const double drawn = normal ? w * standard_normal(draws) : draws.uniform(-w, w);
      if (w != 0.0) out[i] += drawn;  // drawn even so: a width changes no other coordinate's draw
    }
  };
  std::vector<double> qpos0 = scenario.qpos0, qvel0(static_cast<std::size_t>(scenario.nv), 0.0);
  if (!reset.keyframe.empty()) {  // noise about the keyframe's pose (names checked: check_reset)
    const auto k = std::find(scenario.keyframes.begin(), scenario.keyframes.end(), reset.keyframe);
    s.start.keyframe = static_cast<int>(k - scenario.keyframes.begin());
    const auto key = static_cast<std::size_t>(s.start.keyframe);
    std::copy_n(scenario.key_qpos.begin() + static_cast<std::ptrdiff_t>(key * qpos0.size()), qpos0.size(),
                qpos0.begin());
    std::copy_n(scenario.key_qvel.begin() + static_cast<std::ptrdiff_t>(key * qvel0.size()), qvel0.size(),
                qvel0.begin());
  }
  start_at(s.start.qpos, reset.qpos, std::move(qpos0), reset.qpos_noise, true);
  start_at(s.start.qvel, reset.qvel, std::move(qvel0), reset.qvel_noise, false);
  for (const ResetSpec::Goal& g : reset.goals) {
    Schedule::Start::MocapPos goal;
    goal.body = g.body;
    for (const auto& [name, mocap] : scenario.mocap_bodies) {
      if (name == g.body) goal.mocap = mocap;
    }
    for (std::size_t i = 0; i < 3; ++i) goal.pos[i] = draws.uniform(g.low[i], g.high[i]);  // [x, x]: exactly x
    s.start.goals.push_back(goal);
  }
  return s;
}

std::vector<std::pair<std::string, double>> drawn_columns(const Schedule::Start& start) {
  std::vector<std::pair<std::string, double>> out;
  for (const SceneParam& p : start.params) out.emplace_back(scene_param_column(p), p.value);
  for (const Schedule::Start::MocapPos& g : start.goals) {
    for (std::size_t i = 0; i < 3; ++i) out.emplace_back("goal_" + g.body + "_" + "xyz"[i], g.pos[i]);
  }
  return out;
}

}  // namespace simloop
