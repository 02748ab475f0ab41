#include "simloop/sweep.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "divergence.hpp"
#include "simloop/batch.hpp"
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
    throw InvalidArgument("duration " + python_float_repr(duration) + " s at timestep " +
                          python_float_repr(timestep) + " s is " + ratio_text +
                          " steps; a sweep point needs " + std::to_string(kMinSweepSteps) + " to " +
                          std::to_string(kMaxSteps) + " steps (duration / timestep, rounded)");
  }
  return steps;
}

namespace {

// What every sweep shares, whatever its kind of run and its criterion: the
// grid of points, and where the edge lies.
struct GridPoint {
  double timestep;
  std::int64_t steps;  // sweep_steps(duration, timestep)
};

// The timesteps with their steps over `duration` (sweep_steps refuses a point
// that cannot be run faithfully), ascending, duplicates dropped. Ascending
// timesteps put the longest runs first, which keeps a batch's workers evenly
// loaded to the end.
std::vector<GridPoint> sweep_grid(const std::vector<double>& timesteps, double duration) {
  check_positive_seconds("duration", duration);
  if (timesteps.empty()) throw InvalidArgument("timesteps must not be empty");
  std::vector<GridPoint> grid;
  for (const double dt : timesteps) grid.push_back({dt, sweep_steps(duration, dt)});
  const auto earlier = [](const GridPoint& a, const GridPoint& b) { return a.timestep < b.timestep; };
  const auto same = [](const GridPoint& a, const GridPoint& b) { return a.timestep == b.timestep; };
  std::sort(grid.begin(), grid.end(), earlier);
  grid.erase(std::unique(grid.begin(), grid.end(), same), grid.end());
  return grid;
}

// The edge: the last of the points (ascending timesteps) before the first
// that fails the criterion; -1 if even the first fails.
template <class Point, class Passes>
int sweep_edge(const std::vector<Point>& points, Passes passes) {
  int edge = -1;
  for (std::size_t i = 0; i < points.size() && passes(points[i]); ++i) edge = static_cast<int>(i);
  return edge;
}

// Reduces a run's rows to a sweep point's figures as they come, so a sweep
// keeps no trajectories, however many timesteps it has.
class SweepReducer final : public RowSink {
 public:
  void start(int columns, std::int64_t /*rows*/) override { columns_ = columns; }
  void write(const double* rows, std::int64_t count) override {
    for (std::int64_t i = 0; i < count; ++i) {
      const double* row = rows + i * columns_;
      peak_box_z_ = std::max(peak_box_z_, row[ChapterColumns::kBoxZ]);
      max_abs_box_y_ = std::max(max_abs_box_y_, std::fabs(row[ChapterColumns::kBoxY]));
    }
    if (count > 0) {
      const double* last = rows + (count - 1) * columns_;
      final_ = {last[ChapterColumns::kBoxX], last[ChapterColumns::kBoxY], last[ChapterColumns::kBoxZ],
                last[ChapterColumns::kPusherX]};
    }
  }
  void fill(SweepPoint& p) const {
    p.peak_box_z = peak_box_z_;
    p.max_abs_box_y = max_abs_box_y_;
    p.final_box_x = final_[0];
    p.final_box_y = final_[1];
    p.final_box_z = final_[2];
    p.final_pusher_x = final_[3];
  }

 private:
  std::int64_t columns_ = 0;
  double peak_box_z_ = -INFINITY;
  double max_abs_box_y_ = 0.0;
  std::array<double, 4> final_{};
};

}  // namespace

SweepResult sweep(const Model& model, std::vector<double> timesteps, double duration, int threads,
                  RunControl* control) {
  std::vector<RunConfig> configs;
  for (const GridPoint& point : sweep_grid(timesteps, duration)) {
    RunConfig c;
    c.timestep = point.timestep;
    c.steps = point.steps;
    c.perturb = false;
    c.audit_energy = true;
    configs.push_back(c);
  }
  std::vector<SweepReducer> reducers(configs.size());
  std::vector<RowSink*> sinks;
  for (SweepReducer& r : reducers) sinks.push_back(&r);
  const std::vector<RunResult> runs = run_batch(model, configs, sinks, threads, control);

  SweepResult result;
  result.duration = duration;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const RunResult& r = runs[i];
    SweepPoint p;
    p.timestep = r.timestep;
    p.steps = r.metrics.steps;
    reducers[i].fill(p);
    for (const Warning& w : r.warnings) p.warnings += w.count;
    p.energy = r.energy;
    result.points.push_back(p);
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

std::string sweep_csv(const SweepResult& result) {
  std::string out =
      "timestep,steps,peak_box_z,max_abs_box_y,final_box_x,final_box_y,final_box_z,final_pusher_x,warnings,"
      "energy_change,work_actuator,work_passive,work_constraint,work_constraint_positive,energy_unexplained,"
      "stable\n";
  for (const SweepPoint& p : result.points) {
    const double values[] = {p.timestep, p.peak_box_z, p.max_abs_box_y, p.final_box_x, p.final_box_y,
                             p.final_box_z, p.final_pusher_x};
    append_shortest(out, values[0]);
    out += ',' + std::to_string(p.steps);
    for (size_t i = 1; i < std::size(values); ++i) {
      out += ',';
      append_shortest(out, values[i]);
    }
    out += ',' + std::to_string(p.warnings);
    const EnergyTotals& e = p.energy;
    for (double v : {e.energy_end - e.energy_start, e.work_actuator, e.work_passive, e.work_constraint,
                     e.work_constraint_positive, e.unexplained}) {
      out += ',';
      append_shortest(out, v);
    }
    out += p.stable ? ",1\n" : ",0\n";
  }
  return out;
}

namespace {

// Every cell as text first, then each column as wide as its widest cell,
// right-aligned, so the table stays aligned whatever the numbers are; the
// last column left-aligned and unpadded: it carries the edge mark.
std::string aligned_table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> width(header.size());
  for (size_t c = 0; c < header.size(); ++c) {
    width[c] = header[c].size();
    for (const auto& row : rows) width[c] = std::max(width[c], row[c].size());
  }
  std::string out;
  const auto append_row = [&](const std::vector<std::string>& cells) {
    std::string text = " ";
    for (size_t c = 0; c < cells.size(); ++c) {
      const bool last = c + 1 == cells.size();
      const std::string pad(last ? 0 : width[c] - cells[c].size(), ' ');
      text += "  " + (last ? cells[c] : pad + cells[c]);
    }
    out += text + "\n";
  };
  append_row(header);
  for (const auto& row : rows) append_row(row);
  return out;
}

// The line under a sweep's table: where its edge is, or why it has none.
template <class Result>
std::string edge_line(const Result& result, const std::string& label, const std::string& none) {
  if (result.edge_index < 0) return label + ": none (" + none + ")\n";
  return label + ": " + python_float_repr(result.points[static_cast<std::size_t>(result.edge_index)].timestep) + " s\n";
}

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

// What a row of the chapter's sweep is beside the chapter's own runs: the
// sweep runs every timestep for the same sim time, not the chapter's 2000
// steps, so its 0.05 s point is Break It's timestep over 4 s, not Break It.
std::string chapter_marks(const SweepPoint& point, bool edge) {
  const RunConfig chapter;
  std::vector<std::string> marks;
  if (edge) marks.push_back("edge");
  for (const auto& [timestep, name] : {std::pair{chapter.timestep, std::string("the chapter")},
                                       std::pair{kBreakItTimestep, std::string("Break It")}}) {
    if (point.timestep != timestep) continue;
    std::string mark = name + "'s timestep";
    if (point.steps != chapter.steps) {
      char line[128];
      std::snprintf(line, sizeof line, " (%lld steps here; %s runs %lld: %g s)", static_cast<long long>(point.steps),
                    name.c_str(), static_cast<long long>(chapter.steps), static_cast<double>(chapter.steps) * timestep);
      mark += line;
    }
    marks.push_back(mark);
  }
  std::string out;
  for (const std::string& mark : marks) out += (out.empty() ? "  <- " : "; ") + mark;
  return out;
}

}  // namespace

std::string sweep_summary(const SweepResult& result) {
  char line[256];
  std::string out;
  std::snprintf(line, sizeof line, "swept %zu timesteps, %s s of sim time each, no shove\n", result.points.size(),
                python_float_repr(result.duration).c_str());
  out += line;
  const std::vector<std::string> header = {"timestep (s)", "steps", "peak z (m)", "max |y| (m)", "final z (m)",
                                           "contacts +work (J)", "unexplained (J)", "warnings", "stable"};
  std::vector<std::vector<std::string>> rows;
  for (size_t i = 0; i < result.points.size(); ++i) {
    const SweepPoint& p = result.points[i];
    rows.push_back({python_float_repr(p.timestep), std::to_string(p.steps), fixed(p.peak_box_z, 4),
                    fixed(p.max_abs_box_y, 4), fixed(p.final_box_z, 4), fixed(p.energy.work_constraint_positive, 4),
                    fixed(p.energy.unexplained, 4), std::to_string(p.warnings),
                    std::string(p.stable ? "yes" : "no") +
                        chapter_marks(p, static_cast<int>(i) == result.edge_index)});
  }
  out += aligned_table(header, rows);
  out += edge_line(result, "largest stable timestep", "even the finest is unstable");
  std::snprintf(line, sizeof line,
                "  stable: the box rises at most %g mm above rest (%.2f m) and ends at most %g mm below it, and "
                "MuJoCo raised no warning\n",
                kStableHop * 1e3, kBoxRestZ, kStableSink * 1e3);
  out += line;
  return out;
}

// ---------------------------------------------------------------------------
// A scenario, swept.

double scenario_duration(const Model& scene, const Scenario& scenario) {
  switch (scenario.length.unit) {
    case When::Unit::kSeconds: return scenario.length.value;
    case When::Unit::kSteps:
      return static_cast<double>(scenario.length.count) * scenario.timestep.value_or(scene.timestep());
    default: break;
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

// Reduces a scenario run's rows to the largest speed of any recorded body,
// as they come (the final positions are in the result's final row).
class PeakSpeed final : public RowSink {
 public:
  void describe(const std::vector<Column>& columns) override {
    for (const auto& [name, column] : recorded_bodies(columns)) velocity_columns_.push_back(column + 7);
  }
  void start(int columns, std::int64_t /*rows*/) override { columns_ = columns; }
  void write(const double* rows, std::int64_t count) override {
    for (std::int64_t i = 0; i < count; ++i) {
      const double* row = rows + i * columns_;
      for (std::size_t c : velocity_columns_) {
        const double* v = row + c;
        const double speed = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        // A NaN speed (a state gone bad) is the largest of all.
        if (!(speed <= peak_)) peak_ = std::isnan(peak_) ? peak_ : speed;
      }
    }
  }
  [[nodiscard]] double peak() const noexcept { return peak_; }

 private:
  std::vector<std::size_t> velocity_columns_;
  std::int64_t columns_ = 0;
  double peak_ = 0.0;
};

}  // namespace

ScenarioSweepResult sweep_scenario(const Model& scene, const Scenario& scenario, std::vector<double> timesteps,
                                   double duration, const ScenarioConfig& config, int threads, RunControl* control) {
  std::vector<ScenarioConfig> configs;
  for (const GridPoint& point : sweep_grid(timesteps, duration)) {
    ScenarioConfig c = config;
    c.timestep = point.timestep;
    c.steps = point.steps;
    c.record_every = 1;  // every step's speed is read
    configs.push_back(c);
  }
  std::vector<PeakSpeed> reducers(configs.size());
  std::vector<RowSink*> sinks;
  for (PeakSpeed& r : reducers) sinks.push_back(&r);
  const std::vector<RunRecord> runs = run_scenario_batch(scene, scenario, configs, sinks, threads, control);

  ScenarioSweepResult result;
  result.name = scenario.name;
  result.duration = duration;
  result.scene_size = scene.get()->stat.extent;
  result.tolerance = kScenarioSweepTolerance * result.scene_size;
  std::vector<std::pair<std::size_t, std::string>> bodies;  // in the columns' order
  for (const auto& [name, column] : recorded_bodies(runs.front().columns)) bodies.push_back({column, name});
  std::sort(bodies.begin(), bodies.end());
  for (const auto& body : bodies) result.bodies.push_back(body.second);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const RunRecord& r = runs[i];
    ScenarioSweepPoint p;
    p.timestep = r.timestep;
    p.steps = r.schedule.steps;
    p.peak_speed = reducers[i].peak();
    for (const Warning& w : r.warnings) (w.name == detail::kDivergedWarning ? p.diverged : p.mujoco_warnings) += w.count;
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

std::string sweep_csv(const ScenarioSweepResult& result) {
  std::string out = "timestep,steps,mujoco_warnings,diverged,peak_speed";
  for (const std::string& b : result.bodies) out += "," + b + "_final_x," + b + "_final_y," + b + "_final_z," + b + "_offset";
  out += ",max_offset,tolerance,blew_up\n";
  for (const ScenarioSweepPoint& p : result.points) {
    append_shortest(out, p.timestep);
    out += ',' + std::to_string(p.steps) + ',' + std::to_string(p.mujoco_warnings) + ',' + std::to_string(p.diverged) +
           ',';
    append_shortest(out, p.peak_speed);
    for (std::size_t b = 0; b < p.final_positions.size(); ++b) {
      for (double v : {p.final_positions[b][0], p.final_positions[b][1], p.final_positions[b][2], p.offsets[b]}) {
        out += ',';
        append_shortest(out, v);
      }
    }
    out += ',';
    append_shortest(out, p.max_offset);
    out += ',';
    append_shortest(out, result.tolerance);
    out += p.blew_up ? ",1\n" : ",0\n";
  }
  return out;
}

std::string sweep_summary(const ScenarioSweepResult& result) {
  char line[512];
  std::string out;
  std::snprintf(line, sizeof line, "swept scenario %s over %zu timesteps, %s s of sim time each\n",
                result.name.empty() ? "(unnamed)" : result.name.c_str(), result.points.size(),
                python_float_repr(result.duration).c_str());
  out += line;
  std::vector<std::string> header = {"timestep (s)", "steps", "warnings", "diverged", "peak speed (m/s)"};
  for (const std::string& b : result.bodies) header.push_back(b + " off (m)");
  header.push_back("blew up");
  std::vector<std::vector<std::string>> rows;
  for (size_t i = 0; i < result.points.size(); ++i) {
    const ScenarioSweepPoint& p = result.points[i];
    std::vector<std::string> row = {python_float_repr(p.timestep), std::to_string(p.steps),
                                    std::to_string(p.mujoco_warnings), std::to_string(p.diverged),
                                    fixed(p.peak_speed, 3)};
    for (double offset : p.offsets) row.push_back(fixed(offset, 4));
    row.push_back(std::string(p.blew_up ? "yes" : "no") + (i == 0 ? "  (reference)" : "") +
                  (static_cast<int>(i) == result.edge_index ? "  <- edge" : ""));
    rows.push_back(std::move(row));
  }
  out += aligned_table(header, rows);
  out += edge_line(result, "largest timestep before any blew up", "even the finest did");
  std::snprintf(line, sizeof line,
                "  blew up: MuJoCo or simloop_DIVERGED warned, or a recorded body ended more than %s m (%g%% of the "
                "scene's size, %s m) from where the finest timestep left it\n",
                fixed(result.tolerance, 4).c_str(), kScenarioSweepTolerance * 100,
                fixed(result.scene_size, 3).c_str());
  out += line;
  return out;
}

}  // namespace simloop
