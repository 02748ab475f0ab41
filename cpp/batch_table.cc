#include "simloop/batch_table.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

#include "run_detail.hpp"
#include "simloop/scenario.hpp"
#include "warning_counter.hpp"

namespace simloop {

namespace {

// What a row shows of a run, found once for its layout and its values:
// the recorded bodies (by name) and drawn_columns(r.schedule.start).
struct Shown {
  std::map<std::string, std::size_t> bodies;
  std::vector<std::pair<std::string, double>> drawn;
};

// The columns of `r`'s row after the ones every row has (batch_table.hpp).
std::vector<TableColumn> layout_of(const RunRecord& r, const Shown& shown) {
  std::vector<TableColumn> out;
  for (const auto& body : shown.bodies) {
    for (const char* axis : {"x", "y", "z"}) out.push_back({body.first + "_final_pos_" + axis, false});
    out.push_back({body.first + "_final_speed", false});
  }
  for (std::size_t i = 0; i < r.schedule.forces.size(); ++i) {
    const std::string prefix = "disturbance" + std::to_string(i) + "_";
    for (const char* axis : {"fx", "fy", "fz", "tx", "ty", "tz"}) out.push_back({prefix + axis, false});
    out.push_back({prefix + "start_step", true});
    out.push_back({prefix + "steps", true});
  }
  for (const auto& column : shown.drawn) out.push_back({column.first, false});
  return out;
}

std::vector<double> values_of(const RunRecord& r, const Shown& shown) {
  std::vector<double> out;
  for (const auto& body : shown.bodies) {
    const double* v = r.final_row.data() + body.second;  // x y z, qw qx qy qz, vx vy vz
    out.insert(out.end(), {v[0], v[1], v[2], final_speed(v[7], v[8], v[9])});
  }
  for (const Schedule::Force& f : r.schedule.forces) {
    out.insert(out.end(), f.wrench.begin(), f.wrench.end());
    out.insert(out.end(), {static_cast<double>(f.start), static_cast<double>(f.end - f.start)});
  }
  for (const auto& column : shown.drawn) out.push_back(column.second);
  return out;
}

bool same_layout(const std::vector<TableColumn>& a, const std::vector<TableColumn>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [](const TableColumn& x, const TableColumn& y) { return x.name == y.name; });
}

// Rows go into slots made up front, from any worker; the layouts are shared.
class TableBuilder {
 public:
  explicit TableBuilder(std::size_t runs) : names_(detail::all_warning_names()) { table_.rows.resize(runs); }

  void add(std::size_t i, const RunRecord& r) {
    TableRow& row = table_.rows[i];
    row.scenario = r.name;
    row.rng = r.rng;
    row.seed = r.seed;
    row.timestep = r.timestep;
    row.steps = r.schedule.steps;
    row.perturb = r.perturb;
    row.sim_time = r.sim_time;
    const Shown shown{recorded_bodies(r), drawn_columns(r.schedule.start)};
    row.values = values_of(r, shown);
    row.warnings.assign(names_.size(), 0);
    for (const Warning& w : r.warnings) {
      const auto at = std::find(names_.begin(), names_.end(), w.name);
      if (at != names_.end()) row.warnings[static_cast<std::size_t>(at - names_.begin())] += w.count;
    }
    std::vector<TableColumn> layout = layout_of(r, shown);
    const std::lock_guard<std::mutex> hold(lock_);
    auto known = std::find_if(table_.layouts.begin(), table_.layouts.end(),
                              [&](const std::vector<TableColumn>& l) { return same_layout(l, layout); });
    if (known == table_.layouts.end()) known = table_.layouts.insert(known, std::move(layout));
    row.layout = static_cast<std::size_t>(known - table_.layouts.begin());
  }

  // The layouts in the order runs first had them (workers may meet them in another).
  ScenarioTable take() {
    std::vector<std::size_t> order, renumber(table_.layouts.size());
    for (const TableRow& row : table_.rows) {
      if (std::find(order.begin(), order.end(), row.layout) == order.end()) order.push_back(row.layout);
    }
    ScenarioTable out;
    for (std::size_t k = 0; k < order.size(); ++k) {
      renumber[order[k]] = k;
      out.layouts.push_back(std::move(table_.layouts[order[k]]));
    }
    out.rows = std::move(table_.rows);
    for (TableRow& row : out.rows) row.layout = renumber[row.layout];
    return out;
  }

 private:
  std::vector<std::string> names_;
  std::mutex lock_;
  ScenarioTable table_;
};

}  // namespace

double final_speed(double vx, double vy, double vz) noexcept {
  const double speed = std::sqrt(vx * vx + vy * vy + vz * vz);
  if (std::isfinite(speed) || !std::isfinite(vx) || !std::isfinite(vy) || !std::isfinite(vz)) return speed;
  const double scale = std::max({std::fabs(vx), std::fabs(vy), std::fabs(vz)});
  vx /= scale, vy /= scale, vz /= scale;
  return scale * std::sqrt(vx * vx + vy * vy + vz * vz);
}

ScenarioTable scenario_table(const std::vector<const RunRecord*>& records) {
  TableBuilder table(records.size());
  for (std::size_t i = 0; i < records.size(); ++i) table.add(i, *records[i]);
  return table.take();
}

ScenarioTable run_scenario_table(const Model& scene, const Scenario& scenario,
                                 const std::vector<ScenarioConfig>& configs, int threads, RunControl* control,
                                 const std::vector<RunInputs>& inputs) {
  DiscardRows discard;  // stateless: every worker may write to it at once
  TableBuilder table(configs.size());
  detail::for_each_scenario_run(scene, scenario, configs, std::vector<RowSink*>(configs.size(), &discard), threads,
                                control, inputs, {}, [&](std::size_t i, RunRecord&& r) { table.add(i, r); });
  return table.take();
}

}  // namespace simloop
