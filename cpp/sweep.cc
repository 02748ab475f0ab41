#include "simloop/sweep.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

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
  if (!(std::isfinite(duration) && duration > 0.0)) {
    throw InvalidArgument("duration must be a positive, finite number of seconds, got " + python_float_repr(duration));
  }
  if (!(std::isfinite(timestep) && timestep > 0.0)) {
    throw InvalidArgument("timestep must be a positive, finite number of seconds, got " +
                          python_float_repr(timestep));
  }
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

// Reduces a run's rows to a sweep point's figures as they come, so a sweep
// keeps no trajectories, however many timesteps it has.
class SweepReducer final : public RowSink {
 public:
  void start(int columns, std::int64_t /*rows*/) override { columns_ = columns; }
  void write(const double* rows, std::int64_t count) override {
    for (std::int64_t i = 0; i < count; ++i) {
      const double* row = rows + i * columns_;
      peak_box_z_ = std::max(peak_box_z_, row[Trajectory::kBoxZ]);
      max_abs_box_y_ = std::max(max_abs_box_y_, std::fabs(row[Trajectory::kBoxY]));
    }
    if (count > 0) {
      const double* last = rows + (count - 1) * columns_;
      final_ = {last[Trajectory::kBoxX], last[Trajectory::kBoxY], last[Trajectory::kBoxZ],
                last[Trajectory::kPusherX]};
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
  if (!(std::isfinite(duration) && duration > 0.0)) {
    throw InvalidArgument("duration must be a positive, finite number of seconds, got " + python_float_repr(duration));
  }
  if (timesteps.empty()) throw InvalidArgument("timesteps must not be empty");
  std::vector<RunConfig> configs;
  for (double dt : timesteps) {
    RunConfig c;
    c.timestep = dt;
    c.steps = sweep_steps(duration, dt);  // refuses a point that cannot be run faithfully
    c.perturb = false;
    c.audit_energy = true;
    configs.push_back(c);
  }
  std::sort(configs.begin(), configs.end(),
            [](const RunConfig& a, const RunConfig& b) { return a.timestep < b.timestep; });
  configs.erase(std::unique(configs.begin(), configs.end(),
                            [](const RunConfig& a, const RunConfig& b) { return a.timestep == b.timestep; }),
                configs.end());
  // Ascending timesteps put the longest runs first, which keeps the workers
  // evenly loaded to the end.
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
  result.edge_index = -1;
  for (size_t i = 0; i < result.points.size() && result.points[i].stable; ++i) result.edge_index = static_cast<int>(i);
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

std::string sweep_summary(const SweepResult& result) {
  char line[256];
  std::string out;
  std::snprintf(line, sizeof line, "swept %zu timesteps, %s s of sim time each, no shove\n", result.points.size(),
                python_float_repr(result.duration).c_str());
  out += line;
  // Every cell as text first, then each column as wide as its widest cell,
  // so the table stays aligned whatever the numbers are.
  const std::vector<std::string> header = {"timestep (s)", "steps", "peak z (m)", "max |y| (m)", "final z (m)",
                                           "contacts +work (J)", "unexplained (J)", "warnings", "stable"};
  std::vector<std::vector<std::string>> rows;
  const auto fixed = [](double value, int decimals) {
    char text[64];
    std::snprintf(text, sizeof text, "%.*f", decimals, value);
    return std::string(text);
  };
  for (size_t i = 0; i < result.points.size(); ++i) {
    const SweepPoint& p = result.points[i];
    rows.push_back({python_float_repr(p.timestep), std::to_string(p.steps), fixed(p.peak_box_z, 4),
                    fixed(p.max_abs_box_y, 4), fixed(p.final_box_z, 4), fixed(p.energy.work_constraint_positive, 4),
                    fixed(p.energy.unexplained, 4), std::to_string(p.warnings),
                    std::string(p.stable ? "yes" : "no") +
                        (static_cast<int>(i) == result.edge_index ? "  <- edge" : "")});
  }
  std::vector<size_t> width(header.size());
  for (size_t c = 0; c < header.size(); ++c) {
    width[c] = header[c].size();
    for (const auto& row : rows) width[c] = std::max(width[c], row[c].size());
  }
  const auto append_row = [&](const std::vector<std::string>& cells) {
    std::string text = " ";
    for (size_t c = 0; c < cells.size(); ++c) {
      const bool last = c + 1 == cells.size();  // left-aligned, unpadded: it carries the edge mark
      const std::string pad(last ? 0 : width[c] - cells[c].size(), ' ');
      text += "  " + (last ? cells[c] : pad + cells[c]);
    }
    out += text + "\n";
  };
  append_row(header);
  for (const auto& row : rows) append_row(row);
  if (result.edge_index >= 0) {
    std::snprintf(line, sizeof line, "largest stable timestep: %s s\n",
                  python_float_repr(result.points[static_cast<size_t>(result.edge_index)].timestep).c_str());
  } else {
    std::snprintf(line, sizeof line, "largest stable timestep: none (even the finest is unstable)\n");
  }
  out += line;
  std::snprintf(line, sizeof line,
                "  stable: the box rises at most %g mm above rest (%.2f m) and ends at most %g mm below it, and "
                "MuJoCo raised no warning\n",
                kStableHop * 1e3, kBoxRestZ, kStableSink * 1e3);
  out += line;
  return out;
}

}  // namespace simloop
