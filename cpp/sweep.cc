#include "simloop/sweep.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "chapter_detail.hpp"
#include "divergence.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"

namespace simloop {

std::vector<double> log_spaced(double from, double to, int count) {
  if (!(std::isfinite(from) && from > 0.0 && std::isfinite(to) && to >= from)) {
    throw InvalidArgument("timestep range must run from a positive timestep up to a larger one, got " +
                          python_float_repr(from) + " to " + python_float_repr(to));
  }
  if (count < 1 || (count == 1 && to != from)) {
    throw InvalidArgument("timestep count must be at least 2 for a range (1 if from == to), got " +
                          std::to_string(count));
  }
  std::vector<double> out;
  for (int i = 0; i < count; ++i) {
    const double t = count == 1 ? 0.0 : static_cast<double>(i) / (count - 1);
    // Endpoints exactly as given; round the rest to 6 significant digits so
    // the CSV and the table show the timestep that actually ran.
    const double value = i == 0 ? from : i == count - 1 ? to : std::exp(std::log(from) + t * std::log(to / from));
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", value);
    out.push_back(i == 0 || i == count - 1 ? value : std::strtod(text, nullptr));
  }
  return out;
}

std::vector<double> default_sweep_timesteps() {
  return {0.0005, 0.0006, 0.0008, 0.001, 0.002, 0.003, 0.004, 0.005, 0.006, 0.008, 0.01, 0.02, 0.03,
          0.04,   0.05,   0.06,   0.08,  0.1,   0.2,   0.3,   0.4,   0.5,   0.6,   0.8,  1.0};
}

std::int64_t sweep_steps(double duration, double timestep) {
  check_positive_seconds("duration", duration);
  check_positive_seconds("timestep", timestep);
  const double ratio = duration / timestep;  // may be inf
  // 2^62 is exact in a double; below it llround cannot overflow.
  const std::int64_t steps =
      ratio < 4611686018427387904.0 ? std::llround(ratio) : std::numeric_limits<std::int64_t>::max();
  if (steps < kMinSweepSteps || steps > kMaxSteps) {
    char ratio_text[32];
    std::snprintf(ratio_text, sizeof ratio_text, "%.6g", ratio);
    throw InvalidArgument("duration " + python_float_repr(duration) + " s at timestep " + python_float_repr(timestep) +
                          " s is " + ratio_text + " steps; a sweep point needs " + std::to_string(kMinSweepSteps) +
                          " to " + std::to_string(kMaxSteps) + " steps (duration / timestep, rounded)");
  }
  return steps;
}

double scenario_duration(const Model& scene, const Scenario& scenario) {
  switch (scenario.length.unit) {
    case When::Unit::kSeconds:
      return scenario.length.value;
    case When::Unit::kSteps:
      return static_cast<double>(scenario.length.count) * scenario.timestep.value_or(scene.timestep());
    default:
      break;
  }
  throw InvalidArgument("scenario " + scenario.name + ": its length is a fraction of itself; give a duration");
}

std::vector<double> default_scenario_sweep_timesteps(double duration) {
  std::vector<double> out;
  for (double dt : default_sweep_timesteps()) {
    if (std::isfinite(duration) && duration > 0.0 && std::llround(duration / dt) >= kMinSweepSteps) out.push_back(dt);
  }
  return out;
}

namespace {

// The edge: the last of the points (ascending timesteps) before the first
// that fails the criterion; -1 if even the first fails.
template <class Point, class Passes>
int sweep_edge(const std::vector<Point>& points, Passes passes) {
  int edge = -1;
  for (std::size_t i = 0; i < points.size() && passes(points[i]); ++i) edge = static_cast<int>(i);
  return edge;
}

// Reduces a run's rows, as they come, to what a sweep's criteria read of each
// recorded body besides its final position (in the run's final row): its peak
// z and its largest |y|; and the largest speed of any body. A sweep keeps no
// trajectories, however many timesteps it has.
class BodyExtremes final : public RowSink {
 public:
  void describe(const std::vector<Column>& columns) override {
    for (const auto& [name, column] : recorded_bodies(columns)) bodies_.push_back({column, name});
    std::sort(bodies_.begin(), bodies_.end());  // the columns' order
    peak_z_.assign(bodies_.size(), -INFINITY);
    max_abs_y_.assign(bodies_.size(), 0.0);
  }
  void start(int columns, std::int64_t /*rows*/) override { columns_ = columns; }
  void write(const double* rows, std::int64_t count) override {
    for (std::int64_t i = 0; i < count; ++i) {
      for (std::size_t b = 0; b < bodies_.size(); ++b) {
        const double* body = rows + i * columns_ + bodies_[b].first;  // x y z, qw qx qy qz, vx vy vz, wx wy wz
        peak_z_[b] = std::max(peak_z_[b], body[2]);
        max_abs_y_[b] = std::max(max_abs_y_[b], std::fabs(body[1]));
        const double speed = std::sqrt(body[7] * body[7] + body[8] * body[8] + body[9] * body[9]);
        // A NaN speed (a state gone bad) is the largest of all.
        if (!(speed <= peak_speed_)) peak_speed_ = std::isnan(peak_speed_) ? peak_speed_ : speed;
      }
    }
  }
  // Each recorded body's first column and its name, in the columns' order.
  [[nodiscard]] const std::vector<std::pair<std::size_t, std::string>>& bodies() const noexcept { return bodies_; }
  void fill(ScenarioSweepPoint& p) const {
    p.peak_speed = peak_speed_;
    p.peak_z = peak_z_;
    p.max_abs_y = max_abs_y_;
  }

 private:
  std::vector<std::pair<std::size_t, std::string>> bodies_;
  std::int64_t columns_ = 0;
  std::vector<double> peak_z_, max_abs_y_;
  double peak_speed_ = 0.0;
};

}  // namespace

ScenarioSweepResult sweep_scenario(const Model& scene, const Scenario& scenario, std::vector<double> timesteps,
                                   double duration, const ScenarioConfig& config, int threads, RunControl* control) {
  check_positive_seconds("duration", duration);
  if (timesteps.empty()) throw InvalidArgument("timesteps must not be empty");
  for (const double dt : timesteps) (void)sweep_steps(duration, dt);  // each refused as given, before sorting
  // Ascending timesteps put the longest runs first, which keeps a batch's
  // workers evenly loaded to the end.
  std::sort(timesteps.begin(), timesteps.end());
  timesteps.erase(std::unique(timesteps.begin(), timesteps.end()), timesteps.end());
  std::vector<ScenarioConfig> configs;
  for (const double dt : timesteps) {
    ScenarioConfig c = config;
    c.timestep = dt;
    c.steps = sweep_steps(duration, dt);
    c.record_every = 1;  // every step is read (peaks)
    configs.push_back(c);
  }
  std::vector<BodyExtremes> reducers(configs.size());
  std::vector<RowSink*> sinks;
  for (BodyExtremes& r : reducers) sinks.push_back(&r);
  const std::vector<RunRecord> runs = run_scenario_batch(scene, scenario, configs, sinks, threads, control);

  ScenarioSweepResult result;
  result.name = scenario.name;
  result.duration = duration;
  result.scene_size = scene.get()->stat.extent;
  result.tolerance = kScenarioSweepTolerance * result.scene_size;
  result.columns = runs.front().columns;
  const auto& bodies = reducers.front().bodies();
  for (const auto& body : bodies) result.bodies.push_back(body.second);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const RunRecord& r = runs[i];
    ScenarioSweepPoint p;
    p.timestep = r.timestep;
    p.steps = r.schedule.steps;
    reducers[i].fill(p);
    for (const Warning& w : r.warnings)
      (w.name == detail::kDivergedWarning ? p.diverged : p.mujoco_warnings) += w.count;
    p.energy = r.energy;
    p.final_row = r.final_row;
    for (const auto& body : bodies) {
      const double* pos = r.final_row.data() + body.first;
      p.final_positions.push_back({pos[0], pos[1], pos[2]});
    }
    result.points.push_back(std::move(p));
  }
  const ScenarioSweepPoint& reference = result.points.front();
  for (ScenarioSweepPoint& p : result.points) {
    for (std::size_t b = 0; b < p.final_positions.size(); ++b) {
      const auto& a = p.final_positions[b];
      const auto& ref = reference.final_positions[b];
      const double offset = std::sqrt((a[0] - ref[0]) * (a[0] - ref[0]) + (a[1] - ref[1]) * (a[1] - ref[1]) +
                                      (a[2] - ref[2]) * (a[2] - ref[2]));
      p.offsets.push_back(offset);
      if (!(offset <= p.max_offset)) p.max_offset = std::isnan(p.max_offset) ? p.max_offset : offset;
    }
    p.blew_up = p.mujoco_warnings > 0 || p.diverged > 0 || !(p.max_offset <= result.tolerance);
  }
  result.edge_index = sweep_edge(result.points, [](const ScenarioSweepPoint& p) { return !p.blew_up; });
  return result;
}

// ---------------------------------------------------------------------------
// The chapter's sweep: its scenario's, seen as the chapter sees it.

SweepResult sweep(const Model& model, std::vector<double> timesteps, double duration, int threads,
                  RunControl* control) {
  ScenarioConfig baseline;
  baseline.perturb = false;
  baseline.audit_energy = true;
  const ScenarioSweepResult swept =
      sweep_scenario(model, chapter_scenario(model), std::move(timesteps), duration, baseline, threads, control);
  const auto box =
      static_cast<std::size_t>(std::find(swept.bodies.begin(), swept.bodies.end(), "box") - swept.bodies.begin());
  const std::string pusher = detail::pusher_joint_name(model) + "_pos";
  const auto pusher_x = static_cast<std::size_t>(
      std::find_if(swept.columns.begin(), swept.columns.end(), [&](const Column& c) { return c.name == pusher; }) -
      swept.columns.begin());
  SweepResult result;
  result.duration = duration;
  for (const ScenarioSweepPoint& p : swept.points) {
    const std::array<double, 3>& final_box = p.final_positions.at(box);
    result.points.push_back({p.timestep, p.steps, p.peak_z.at(box), p.max_abs_y.at(box), final_box[0], final_box[1],
                             final_box[2], p.final_row.at(pusher_x), p.mujoco_warnings + p.diverged, p.energy});
  }
  judge_sweep(result);
  return result;
}

void judge_sweep(SweepResult& result) {
  for (SweepPoint& p : result.points) {
    p.stable = p.peak_box_z <= kBoxRestZ + kStableHop && p.final_box_z >= kBoxRestZ - kStableSink && p.warnings == 0;
  }
  result.edge_index = sweep_edge(result.points, [](const SweepPoint& p) { return p.stable; });
}

SweepResult join_sweeps(const std::vector<SweepResult>& parts) {
  if (parts.empty()) throw InvalidArgument("join_sweeps needs at least one sweep, got none");
  SweepResult joined;
  joined.duration = parts.front().duration;
  for (const SweepResult& part : parts) {
    if (part.duration != joined.duration) {
      throw InvalidArgument("join_sweeps: the sweeps' durations differ, " + python_float_repr(joined.duration) +
                            " and " + python_float_repr(part.duration));
    }
    for (const SweepPoint& p : part.points) {
      if (!joined.points.empty() && !(p.timestep > joined.points.back().timestep)) {
        throw InvalidArgument("join_sweeps: the sweeps' timesteps do not ascend at " + python_float_repr(p.timestep));
      }
      joined.points.push_back(p);
    }
  }
  judge_sweep(joined);
  return joined;
}

}  // namespace simloop
