// What a sweep prints: its CSV and its summary table, for the chapter's
// sweep and a scenario's (the sweeps themselves are in sweep.cc).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <string>
#include <vector>

#include "simloop/number_format.hpp"
#include "simloop/sweep.hpp"

namespace simloop {
namespace {

// Each value after a comma, as the shortest text that reads back the same.
void append_cells(std::string& out, std::initializer_list<double> values) {
  for (const double v : values) {
    out += ',';
    append_shortest(out, v);
  }
}

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

std::string sweep_csv(const SweepResult& result) {
  std::string out =
      "timestep,steps,peak_box_z,max_abs_box_y,final_box_x,final_box_y,final_box_z,final_pusher_x,warnings,"
      "energy_change,work_actuator,work_passive,work_constraint,work_constraint_positive,energy_unexplained,"
      "stable\n";
  for (const SweepPoint& p : result.points) {
    append_shortest(out, p.timestep);
    out += ',' + std::to_string(p.steps);
    append_cells(out, {p.peak_box_z, p.max_abs_box_y, p.final_box_x, p.final_box_y, p.final_box_z, p.final_pusher_x});
    out += ',' + std::to_string(p.warnings);
    const EnergyTotals& e = p.energy;
    append_cells(out, {e.energy_end - e.energy_start, e.work_actuator, e.work_passive, e.work_constraint,
                       e.work_constraint_positive, e.unexplained});
    out += p.stable ? ",1\n" : ",0\n";
  }
  return out;
}

std::string sweep_summary(const SweepResult& result) {
  char line[256];
  std::string out;
  std::snprintf(line, sizeof line, "swept %zu timestep%s, %s s of sim time each, no shove\n", result.points.size(),
                result.points.size() == 1 ? "" : "s", python_float_repr(result.duration).c_str());
  out += line;
  const std::vector<std::string> header = {"timestep (s)",    "steps",       "peak z (m)",
                                           "max |y| (m)",     "final z (m)", "contacts +work (J)",
                                           "unexplained (J)", "warnings",    "stable"};
  std::vector<std::vector<std::string>> rows;
  for (size_t i = 0; i < result.points.size(); ++i) {
    const SweepPoint& p = result.points[i];
    rows.push_back({python_float_repr(p.timestep), std::to_string(p.steps), fixed(p.peak_box_z, 4),
                    fixed(p.max_abs_box_y, 4), fixed(p.final_box_z, 4), fixed(p.energy.work_constraint_positive, 4),
                    fixed(p.energy.unexplained, 4), std::to_string(p.warnings),
                    std::string(p.stable ? "yes" : "no") + chapter_marks(p, static_cast<int>(i) == result.edge_index)});
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

std::string sweep_csv(const ScenarioSweepResult& result) {
  std::string out = "timestep,steps,mujoco_warnings,diverged,peak_speed";
  for (const std::string& b : result.bodies)
    out += "," + b + "_final_x," + b + "_final_y," + b + "_final_z," + b + "_offset";
  out += ",max_offset,tolerance,blew_up\n";
  for (const ScenarioSweepPoint& p : result.points) {
    append_shortest(out, p.timestep);
    out += ',' + std::to_string(p.steps) + ',' + std::to_string(p.mujoco_warnings) + ',' + std::to_string(p.diverged);
    append_cells(out, {p.peak_speed});
    for (std::size_t b = 0; b < p.final_positions.size(); ++b) {
      append_cells(out, {p.final_positions[b][0], p.final_positions[b][1], p.final_positions[b][2], p.offsets[b]});
    }
    append_cells(out, {p.max_offset, result.tolerance});
    out += p.blew_up ? ",1\n" : ",0\n";
  }
  return out;
}

std::string sweep_summary(const ScenarioSweepResult& result) {
  char line[512];
  std::string out;
  std::snprintf(line, sizeof line, "swept scenario %s over %zu timestep%s, %s s of sim time each\n",
                result.name.empty() ? "(unnamed)" : result.name.c_str(), result.points.size(),
                result.points.size() == 1 ? "" : "s", python_float_repr(result.duration).c_str());
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
                fixed(result.tolerance, 4).c_str(), kScenarioSweepTolerance * 100, fixed(result.scene_size, 3).c_str());
  out += line;
  return out;
}

}  // namespace simloop
