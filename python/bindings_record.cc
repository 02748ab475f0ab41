// simloop._core's run record: what any run leaves (ScenarioResult in Python;
// the chapter's RunResult is one, with the chapter's report on top), and
// the warnings it holds.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <string>
#include <utility>

#include "bindings_common.hpp"
#include "simloop/batch_table.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"
#include "simloop/output.hpp"
#include "simloop/run_record.hpp"
#include "simloop/scene_params.hpp"

namespace simloop_py {

using namespace pybind11::literals;
using simloop::RunRecord;

namespace {

// A run's trajectory as a (rows, columns) read-only view of its own buffer,
// and one column of it as a strided view. No copy.
inline py::array trajectory_view(const py::object& owner, const simloop::Trajectory& t) {
  const auto item = static_cast<py::ssize_t>(sizeof(double));
  return read_only(py::array(py::dtype::of<double>(),
                             {static_cast<py::ssize_t>(t.rows()), static_cast<py::ssize_t>(t.columns())},
                             {item * t.columns(), item}, t.data(), owner));
}
inline py::array column_view(const py::object& owner, const simloop::Trajectory& t, int column) {
  const auto item = static_cast<py::ssize_t>(sizeof(double));
  return read_only(py::array(py::dtype::of<double>(), {static_cast<py::ssize_t>(t.rows())}, {item * t.columns()},
                             t.data() + column, owner));
}

// A column's index by its name, as a str (a name UTF-8 cannot encode is in
// no result: KeyError too).
int column_index(const RunRecord& r, const py::handle& name) {
  if (!py::isinstance<py::str>(name)) throw py::type_error("name must be a str (a column name), got " + describe(name));
  for (size_t c = 0; c < r.columns.size(); ++c) {
    if (py::str(r.columns[c].name).equal(name)) return static_cast<int>(c);
  }
  std::vector<std::string> names;
  for (const simloop::Column& c : r.columns) names.push_back(c.name);
  std::string hint;
  try {
    hint = simloop::did_you_mean(name.cast<std::string>(), names);
  } catch (const py::cast_error&) {  // text UTF-8 cannot encode: like no column's name
  }
  throw py::key_error("no trajectory column named " + show(name) +
                      (hint.empty() ? "" : " (did you mean '" + hint + "'?)") + "; see result.column_names");
}

}  // namespace

void bind_record(py::module_& m) {
  py::class_<simloop::Warning>(m, "MujocoWarning", "A warning MuJoCo raised while stepping.")
      .def_readonly("name", &simloop::Warning::name)
      .def_readonly("count", &simloop::Warning::count)
      .def_readonly("first_step", &simloop::Warning::first_step)
      .def_readonly("message", &simloop::Warning::message)
      .def("__repr__", [](const simloop::Warning& w) {
        return "MujocoWarning(" + w.name + ", count=" + std::to_string(w.count) +
               ", first_step=" + std::to_string(w.first_step) + ")";
      });

  py::class_<RunRecord>(m, "ScenarioResult", "What one run did: its schedule, rows, final state and warnings.")
      .def_readonly("name", &RunRecord::name, "The scenario's name.")
      .def_readonly("seed", &RunRecord::seed)
      .def_readonly("rng", &RunRecord::rng)
      .def_readonly("perturb", &RunRecord::perturb)
      .def_readonly("rows", &RunRecord::rows, "Trajectory rows the run recorded, kept or streamed.")
      .def_readonly("timestep", &RunRecord::timestep)
      .def_readonly("sim_time", &RunRecord::sim_time)
      .def_readonly("warnings", &RunRecord::warnings)
      .def_property_readonly("steps", [](const RunRecord& r) { return r.schedule.steps; })
      .def_property_readonly(
          "energy",
          [](const RunRecord& r) -> py::object {
            if (!simloop::audited(r)) return py::none();
            const simloop::EnergyTotals& e = r.energy;
            return py::dict("energy_start"_a = e.energy_start, "energy_end"_a = e.energy_end,
                            "work_actuator"_a = e.work_actuator, "work_shove"_a = e.work_shove,
                            "work_passive"_a = e.work_passive, "work_constraint"_a = e.work_constraint,
                            "work_constraint_positive"_a = e.work_constraint_positive, "unexplained"_a = e.unexplained);
          },
          "The energy audit's totals, J (None unless audit_energy).")
      .def_property_readonly("column_names",
                             [](const RunRecord& r) {
                               py::tuple names(r.columns.size());
                               for (size_t i = 0; i < r.columns.size(); ++i) names[i] = py::str(r.columns[i].name);
                               return names;
                             })
      .def_property_readonly("column_units",
                             [](const RunRecord& r) {
                               py::dict units;
                               for (const simloop::Column& c : r.columns) units[py::str(c.name)] = c.unit;
                               return units;
                             })
      .def_property_readonly(
          "trajectory",
          [](const py::object& self) { return trajectory_view(self, self.cast<const RunRecord&>().trajectory); },
          "(rows, columns) read-only float64 view; columns as in column_names.")
      .def(
          "column",
          [](const py::object& self, const py::object& name) {
            const auto& r = self.cast<const RunRecord&>();
            return column_view(self, r.trajectory, column_index(r, name));
          },
          "name"_a, "One trajectory column as a read-only (strided) view (no copy).")
      .def_property_readonly(
          "columns",
          [](const py::object& self) {
            const auto& r = self.cast<const RunRecord&>();
            py::dict columns;
            for (int c = 0; c < r.trajectory.columns(); ++c) {
              columns[py::str(r.columns[static_cast<size_t>(c)].name)] = column_view(self, r.trajectory, c);
            }
            return columns;
          },
          "Every trajectory column by name, as read-only views (no copy).")
      .def_property_readonly(
          "disturbances",
          [](const RunRecord& r) {
            py::list out;
            for (size_t i = 0; i < r.schedule.forces.size(); ++i) {
              const simloop::Schedule::Force& f = r.schedule.forces[i];
              out.append(py::dict("body"_a = r.disturbed_bodies[i], "force"_a = vec(f.wrench.data(), 3),
                                  "torque"_a = vec(f.wrench.data() + 3, 3), "start_step"_a = f.start,
                                  "end_step"_a = f.end, "asked_end_step"_a = f.asked_end));
            }
            return out;
          })
      .def_property_readonly(
          "params",
          [](const RunRecord& r) {
            py::list out;
            for (const simloop::SceneParam& p : r.schedule.start.params) {
              py::dict param("kind"_a = simloop::scene_param_kind_name(p.kind), "name"_a = p.name, "value"_a = p.value);
              if (p.kind == simloop::SceneParam::Kind::kModel) {
                param["field"] = p.field;
                param["index"] = p.index;
              }
              out.append(param);
            }
            return out;
          },
          "The scene parameters the run drew at its reset ([[reset.param]]), as applied: kind, name, value (and a "
          "model value's field and index).")
      .def_property_readonly(
          "bodies", [](const RunRecord& r) { return simloop::recorded_bodies(r); },
          "The recorded bodies: {name: the column of its _x}.")
      .def_property_readonly(
          "final_row", [](const RunRecord& r) { return vector_array(r.final_row); },
          "The last row (columns as column_names), kept or not: a copy.")
      .def_property_readonly(
          "final_state", [](const RunRecord& r) { return vector_array(r.final_state); },
          "The full state at the end (the flat layout of state.hpp): an initial_state that continues this run.")
      .def_property_readonly(
          "metrics",
          [](const RunRecord& r) { return py::module_::import("json").attr("loads")(simloop::metrics_json(r)); },
          "The dict metrics.json holds (floats rounded to 6 decimals).")
      .def("metrics_json", no_arguments<RunRecord, &simloop::metrics_json>("ScenarioResult.metrics_json"),
           "metrics.json's text.")
      .def("summary", no_arguments<RunRecord, &simloop::summary_text>("ScenarioResult.summary"),
           "The lines the command prints about the run.")
      .def(
          "trajectory_csv",
          [](const RunRecord& r) {
            py::gil_scoped_release release;
            return naming_failures("trajectory_csv", [&] { return simloop::trajectory_csv(r.trajectory, r.columns); });
          },
          "trajectory.csv's text.")
      .def("write", &write_result<RunRecord>, "out"_a,
           "Writes metrics.json and trajectory.csv into out (a directory, made if missing), the bytes the command "
           "writes; returns their paths.")
      .def("__repr__",
           [](const RunRecord& r) {
             return "ScenarioResult(name=" + py_str_repr(r.name) + ", seed=" + std::to_string(r.seed) +
                    ", steps=" + std::to_string(r.schedule.steps) +
                    ", timestep=" + simloop::python_float_repr(r.timestep) +
                    ", rows=" + std::to_string(r.trajectory.rows()) + ", columns=" + std::to_string(r.columns.size()) +
                    ", disturbances=" + std::to_string(r.schedule.forces.size()) +
                    ", warnings=" + std::to_string(r.warnings.size()) + ")";
           })
      .def(pickle_as_bytes<RunRecord, &simloop::record_from_bytes>());

  // A batch's table (batch_table.hpp) as arrays, from which tables.py lays out its BatchTable.
  py::class_<simloop::ScenarioTable>(m, "ScenarioTable", "One row per run of a batch, as numbers.")
      .def("arrays", [](const simloop::ScenarioTable& t) {
        const std::size_t n = t.rows.size();
        py::array_t<std::uint64_t> seed(n);
        py::array_t<double> timestep(n), sim_time(n);
        py::array_t<std::int64_t> steps(n), layout(n);
        py::array_t<bool> perturb(n);
        const std::size_t width = n ? t.rows[0].warnings.size() : 0;
        py::array_t<std::int64_t> warnings({n, width});
        py::list scenario, rng, layouts, values;
        std::vector<std::vector<double>> by_layout(t.layouts.size());
        for (std::size_t i = 0; i < n; ++i) {
          const simloop::TableRow& row = t.rows[i];
          scenario.append(row.scenario), rng.append(row.rng);
          seed.mutable_at(i) = row.seed, timestep.mutable_at(i) = row.timestep, steps.mutable_at(i) = row.steps;
          perturb.mutable_at(i) = row.perturb, sim_time.mutable_at(i) = row.sim_time;
          layout.mutable_at(i) = static_cast<std::int64_t>(row.layout);
          std::copy(row.warnings.begin(), row.warnings.end(), warnings.mutable_data(i, 0));
          by_layout[row.layout].insert(by_layout[row.layout].end(), row.values.begin(), row.values.end());
        }
        for (std::size_t k = 0; k < t.layouts.size(); ++k) {
          py::list columns;
          for (const simloop::TableColumn& c : t.layouts[k]) columns.append(py::make_tuple(c.name, c.integer));
          layouts.append(columns);
          const std::size_t cols = t.layouts[k].size(), rows = cols ? by_layout[k].size() / cols : 0;
          values.append(py::array_t<double>({rows, cols}, by_layout[k].data()));
        }
        return py::dict("scenario"_a = scenario, "seed"_a = seed, "rng"_a = rng, "timestep"_a = timestep,
                        "steps"_a = steps, "perturb"_a = perturb, "sim_time"_a = sim_time, "layout"_a = layout,
                        "layouts"_a = layouts, "values"_a = values, "warnings"_a = warnings);
      });
  m.def("scenario_table", &simloop::scenario_table, "records"_a, "The table of these ScenarioResults.");
}

}  // namespace simloop_py
