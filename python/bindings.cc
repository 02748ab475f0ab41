// simloop._core: glue between the C++ library and Python. No simulation logic
// lives here: arguments are converted, the GIL is released around the C++
// work, and results are handed back as numpy views or plain Python values.
// Argument checking with Python's words lives in python/simloop/_api.py.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli_options.hpp"
#include "simloop/batch.hpp"
#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/number_format.hpp"
#include "simloop/output.hpp"
#include "simloop/run.hpp"
#include "simloop/sim.hpp"
#include "simloop/sweep.hpp"
#include "simloop/version.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

using simloop::RunResult;
using simloop::Trajectory;

py::dict metrics_dict(const simloop::Metrics& m) {
  py::dict d;
  d["box_final_pos"] = py::list(py::cast(std::vector<double>(m.box_final_pos.begin(), m.box_final_pos.end())));
  d["box_final_speed"] = m.box_final_speed;
  d["lateral_drift"] = m.lateral_drift;
  d["perturb"] = m.perturb;
  d["pusher_final_x"] = m.pusher_final_x;
  d["seed"] = m.seed;
  d["shove_moved_box"] = m.shove_moved_box;
  d["steps"] = m.steps;
  return d;
}

// The trajectory as a (rows, columns) read-only view of the result's own
// row-major buffer. No copy.
py::array trajectory_view(const py::object& owner) {
  const Trajectory& t = owner.cast<const RunResult&>().trajectory;
  const auto rows = static_cast<py::ssize_t>(t.rows());
  py::array view(py::dtype::of<double>(), {rows, static_cast<py::ssize_t>(t.columns())},
                 {static_cast<py::ssize_t>(sizeof(double)) * t.columns(),
                  static_cast<py::ssize_t>(sizeof(double))},
                 t.data(), owner);
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

py::array column_view(const py::object& owner, int column) {
  const Trajectory& t = owner.cast<const RunResult&>().trajectory;
  py::array view(py::dtype::of<double>(), {static_cast<py::ssize_t>(t.rows())},
                 {static_cast<py::ssize_t>(sizeof(double)) * t.columns()}, t.data() + column, owner);
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

int column_index(const Trajectory& t, const std::string& name) {
  for (int c = 0; c < t.columns(); ++c) {
    if (Trajectory::kColumnNames[c] == name) return c;
  }
  throw py::key_error("no trajectory column named '" + name + "'; see result.column_names");
}

py::tuple column_names(int first, int end) {
  py::tuple names(static_cast<size_t>(end - first));
  for (int c = first; c < end; ++c) {
    names[static_cast<size_t>(c - first)] = py::str(std::string(Trajectory::kColumnNames[c]));
  }
  return names;
}

simloop::ShoveRng shove_rng(const std::string& name) {
  const std::optional<simloop::ShoveRng> rng = simloop::parse_rng(name);
  if (!rng) throw py::value_error("rng must be 'mt19937_64' or 'numpy', got '" + name + "'");
  return *rng;
}

py::array vec(const double* values, size_t n) { return py::array_t<double>(static_cast<py::ssize_t>(n), values); }

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "simloop's compiled core: the chapter's MuJoCo loop in C++ (use the simloop package).";
  m.attr("__version__") = simloop::kVersion;
  m.attr("MUJOCO_VERSION") = simloop::mujoco_version();
  m.attr("PUSHER_SCENE_XML") = std::string(simloop::pusher_scene_xml());
  m.attr("COLUMN_NAMES") = column_names(0, Trajectory::kNumBaseColumns);
  m.attr("ENERGY_COLUMN_NAMES") = column_names(Trajectory::kNumBaseColumns, Trajectory::kNumColumns);
  m.attr("SMOKE_STEPS") = simloop::kSmokeSteps;
  m.attr("SHOVE_STEPS") = simloop::kShoveSteps;

  static py::exception<simloop::MujocoError> mujoco_error(m, "MujocoError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const simloop::MujocoError& e) {
      py::set_error(mujoco_error, e.what());
    } catch (const simloop::InvalidArgument& e) {
      py::set_error(PyExc_ValueError, e.what());
    } catch (const simloop::IoError& e) {
      py::set_error(PyExc_OSError, e.what());
    } catch (const simloop::Error& e) {
      py::set_error(PyExc_RuntimeError, e.what());
    }
  });

  py::class_<simloop::Model>(m, "Model", "A compiled MuJoCo world: read-only, shared by every run on it.")
      .def_static("pusher_scene", &simloop::Model::pusher_scene, "The chapter's scene.")
      .def_static("from_xml_string", &simloop::Model::from_xml_string, "xml"_a, "source"_a = "<string>",
                  "Compiles MJCF text; it needs a body 'box' on a free joint and an actuator 0 on a slide or "
                  "hinge joint.")
      .def_static("from_file", &simloop::Model::from_file, "path"_a, "Compiles an MJCF file.")
      .def("with_timestep", &simloop::Model::with_timestep, "timestep"_a, "A copy with opt.timestep set.")
      .def_property_readonly("timestep", &simloop::Model::timestep)
      .def_property_readonly("nq", [](const simloop::Model& model) { return model.get()->nq; })
      .def_property_readonly("nv", [](const simloop::Model& model) { return model.get()->nv; })
      .def_property_readonly("nu", [](const simloop::Model& model) { return model.get()->nu; })
      .def("__repr__", [](const simloop::Model& model) {
        return "<simloop.Model nq=" + std::to_string(model.get()->nq) + " nv=" + std::to_string(model.get()->nv) +
               " timestep=" + simloop::python_float_repr(model.timestep()) + ">";
      });

  py::class_<simloop::RunConfig>(m, "RunConfig")
      .def(py::init([](std::uint64_t seed, std::int64_t steps, double timestep, bool perturb, bool smoke,
                       std::int64_t record_every, bool audit_energy, const std::string& rng) {
             return simloop::RunConfig{seed, steps, timestep, perturb, smoke, record_every, audit_energy,
                                       shove_rng(rng)};
           }),
           "seed"_a, "steps"_a, "timestep"_a, "perturb"_a, "smoke"_a, "record_every"_a, "audit_energy"_a = false,
           "rng"_a = "mt19937_64")
      .def_property_readonly("rng", [](const simloop::RunConfig& c) { return std::string(simloop::rng_name(c.rng)); })
      .def_readonly("audit_energy", &simloop::RunConfig::audit_energy)
      .def_readonly("seed", &simloop::RunConfig::seed)
      .def_readonly("steps", &simloop::RunConfig::steps)
      .def_readonly("timestep", &simloop::RunConfig::timestep)
      .def_readonly("perturb", &simloop::RunConfig::perturb)
      .def_readonly("smoke", &simloop::RunConfig::smoke)
      .def_readonly("record_every", &simloop::RunConfig::record_every);

  py::class_<simloop::Shove>(m, "Shove", "The sideways shove drawn for a run (applied only if perturb).")
      .def_readonly("newtons", &simloop::Shove::newtons)
      .def_readonly("sign", &simloop::Shove::sign)
      .def_readonly("start_step", &simloop::Shove::start_step)
      .def_readonly("steps", &simloop::Shove::num_steps)
      .def_property_readonly("force_y", &simloop::Shove::force_y)
      .def_property_readonly("rng", [](const simloop::Shove& s) { return std::string(simloop::rng_name(s.rng)); },
                             "The generator that drew it: 'mt19937_64' or 'numpy'.")
      .def("__repr__", [](const simloop::Shove& s) {
        return "Shove(newtons=" + simloop::python_float_repr(s.newtons) + ", sign=" +
               simloop::python_float_repr(s.sign) + ", start_step=" + std::to_string(s.start_step) +
               ", steps=" + std::to_string(s.num_steps) + ", rng='" + std::string(simloop::rng_name(s.rng)) + "')";
      });
  m.def(
      "draw_shove",
      [](std::uint64_t seed, std::int64_t steps, const std::string& rng) {
        return simloop::draw_shove(seed, steps, shove_rng(rng));
      },
      "seed"_a, "steps"_a = 2000, "rng"_a = "mt19937_64", "The shove a run of `steps` steps draws from `seed`.");

  py::class_<simloop::Warning>(m, "MujocoWarning", "A warning MuJoCo raised while stepping.")
      .def_readonly("name", &simloop::Warning::name)
      .def_readonly("count", &simloop::Warning::count)
      .def_readonly("first_step", &simloop::Warning::first_step)
      .def_readonly("message", &simloop::Warning::message)
      .def("__repr__", [](const simloop::Warning& w) {
        return "MujocoWarning(" + w.name + ", count=" + std::to_string(w.count) +
               ", first_step=" + std::to_string(w.first_step) + ")";
      });

  py::class_<RunResult>(m, "RunResult", "What one run did: metrics, trajectory, shove, warnings.")
      .def_property_readonly("metrics", [](const RunResult& r) { return metrics_dict(r.metrics); },
                             "The dict metrics.json holds (floats rounded to 6 decimals).")
      .def_property_readonly("trajectory", [](const py::object& self) { return trajectory_view(self); },
                             "(rows, columns) read-only float64 view; columns as in COLUMN_NAMES.")
      .def(
          "column",
          [](const py::object& self, const std::string& name) {
            return column_view(self, column_index(self.cast<const RunResult&>().trajectory, name));
          },
          "name"_a, "One trajectory column as a read-only (strided) view (no copy).")
      .def_property_readonly(
          "columns",
          [](const py::object& self) {
            py::dict columns;
            for (int c = 0; c < self.cast<const RunResult&>().trajectory.columns(); ++c) {
              columns[py::str(std::string(Trajectory::kColumnNames[c]))] = column_view(self, c);
            }
            return columns;
          },
          "Every trajectory column by name, as read-only views (no copy).")
      .def_property_readonly(
          "column_names",
          [](const RunResult& r) { return column_names(0, r.trajectory.columns()); },
          "This result's trajectory columns (COLUMN_NAMES, then ENERGY_COLUMN_NAMES with the audit).")
      .def_property_readonly(
          "energy",
          [](const RunResult& r) -> py::object {
            if (!r.config.audit_energy) return py::none();
            const simloop::EnergyTotals& e = r.energy;
            py::dict d;
            d["energy_start"] = e.energy_start;
            d["energy_end"] = e.energy_end;
            d["work_actuator"] = e.work_actuator;
            d["work_shove"] = e.work_shove;
            d["work_passive"] = e.work_passive;
            d["work_constraint"] = e.work_constraint;
            d["work_constraint_positive"] = e.work_constraint_positive;
            d["unexplained"] = e.unexplained;
            return std::move(d);
          },
          "The energy audit's totals, J (None unless audit_energy).")
      .def_property_readonly("rows", [](const RunResult& r) { return r.trajectory.rows(); },
                             "Trajectory rows (without building a numpy view).")
      .def_property_readonly("shove", [](const RunResult& r) { return r.shove; })
      .def_property_readonly("warnings", [](const RunResult& r) { return r.warnings; })
      .def_property_readonly("config", [](const RunResult& r) { return r.config; })
      .def_property_readonly("timestep", [](const RunResult& r) { return r.timestep; })
      .def_property_readonly("sim_time", [](const RunResult& r) { return r.sim_time; })
      .def("metrics_json", [](const RunResult& r) { return simloop::metrics_json(r.metrics); })
      .def("trajectory_csv", [](const RunResult& r) {
        std::string text;
        {
          py::gil_scoped_release release;
          text = simloop::trajectory_csv(r.trajectory);
        }
        return text;
      })
      .def("summary", [](const RunResult& r) { return simloop::summary_text(r); })
      .def(
          "write",
          [](const RunResult& r, const std::filesystem::path& out) {
            py::gil_scoped_release release;
            const simloop::OutputFiles files = simloop::write_outputs(r, out);
            return std::make_pair(files.metrics, files.trajectory);
          },
          "out"_a);

  m.def(
      "run",
      [](const simloop::Model& model, const simloop::RunConfig& config) {
        py::gil_scoped_release release;
        return simloop::run(model, config);
      },
      "model"_a, "config"_a);
  m.def(
      "run_batch",
      [](const simloop::Model& model, const std::vector<simloop::RunConfig>& configs, int threads) {
        py::gil_scoped_release release;
        return simloop::run_batch(model, configs, threads);
      },
      "model"_a, "configs"_a, "threads"_a);
  m.def("batch_workers", &simloop::batch_workers, "threads"_a, "jobs"_a);

  py::class_<simloop::Contact>(m, "Contact")
      .def_readonly("geom1", &simloop::Contact::geom1)
      .def_readonly("geom2", &simloop::Contact::geom2)
      .def_readonly("dist", &simloop::Contact::dist)
      .def_property_readonly("pos", [](const simloop::Contact& c) { return vec(c.pos.data(), 3); })
      .def("__repr__", [](const simloop::Contact& c) {
        return "Contact(" + c.geom1 + ", " + c.geom2 + ", dist=" + simloop::python_float_repr(c.dist) + ")";
      });

  py::class_<simloop::Sim>(m, "Sim")
      .def(py::init<const simloop::Model&>(), "model"_a)
      .def("reset", &simloop::Sim::reset)
      .def("set_timestep", &simloop::Sim::set_timestep, "timestep"_a)
      .def_property_readonly("timestep", &simloop::Sim::timestep)
      .def("set_ctrl", &simloop::Sim::set_ctrl, "value"_a)
      .def_property_readonly("ctrl", &simloop::Sim::ctrl)
      .def("apply_force", &simloop::Sim::apply_force, "force"_a)
      .def("clear_force", &simloop::Sim::clear_force)
      .def_property_readonly("applied_force", [](const simloop::Sim& s) { return vec(s.applied_force().data(), 3); })
      .def("step", [](simloop::Sim& s, std::int64_t n) { s.step(n); }, "n"_a,
           py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("time", &simloop::Sim::time)
      .def_property_readonly("steps_taken", &simloop::Sim::steps_taken)
      .def_property_readonly("box_position", [](const simloop::Sim& s) { return vec(s.box_position().data(), 3); })
      .def_property_readonly("box_quaternion", [](const simloop::Sim& s) { return vec(s.box_quaternion().data(), 4); })
      .def_property_readonly("box_velocity", [](const simloop::Sim& s) { return vec(s.box_velocity().data(), 3); })
      .def_property_readonly("pusher_x", &simloop::Sim::pusher_x)
      .def_property_readonly("pusher_velocity", &simloop::Sim::pusher_velocity)
      .def_property_readonly("contacts", &simloop::Sim::contacts)
      .def_property_readonly("warnings", &simloop::Sim::warnings);

  m.def("pusher_track", [](const simloop::Model& model) {
    const simloop::PusherTrack t = simloop::pusher_track(model);
    return py::make_tuple(vec(t.rest_position.data(), 3), vec(t.axis.data(), 3), t.q0);
  });

  py::class_<simloop::SweepPoint>(m, "SweepPoint", "One timestep of a sweep.")
      .def_readonly("timestep", &simloop::SweepPoint::timestep)
      .def_readonly("steps", &simloop::SweepPoint::steps)
      .def_readonly("peak_box_z", &simloop::SweepPoint::peak_box_z)
      .def_readonly("max_abs_box_y", &simloop::SweepPoint::max_abs_box_y)
      .def_readonly("final_box_x", &simloop::SweepPoint::final_box_x)
      .def_readonly("final_box_y", &simloop::SweepPoint::final_box_y)
      .def_readonly("final_box_z", &simloop::SweepPoint::final_box_z)
      .def_readonly("final_pusher_x", &simloop::SweepPoint::final_pusher_x)
      .def_readonly("warnings", &simloop::SweepPoint::warnings)
      .def_property_readonly("work_constraint_positive",
                             [](const simloop::SweepPoint& p) { return p.energy.work_constraint_positive; })
      .def_property_readonly("energy_unexplained", [](const simloop::SweepPoint& p) { return p.energy.unexplained; })
      .def_property_readonly("energy_change",
                             [](const simloop::SweepPoint& p) { return p.energy.energy_end - p.energy.energy_start; })
      .def_readonly("stable", &simloop::SweepPoint::stable)
      .def("__repr__", [](const simloop::SweepPoint& p) {
        return "SweepPoint(timestep=" + simloop::python_float_repr(p.timestep) +
               ", stable=" + (p.stable ? "True" : "False") + ")";
      });
  py::class_<simloop::SweepResult>(m, "SweepResult", "A timestep sweep of the baseline run.")
      .def_readonly("duration", &simloop::SweepResult::duration)
      .def_readonly("points", &simloop::SweepResult::points)
      .def_property_readonly("edge", [](const simloop::SweepResult& r) -> py::object {
        if (r.edge_index < 0) return py::none();
        return py::float_(r.points[static_cast<size_t>(r.edge_index)].timestep);
      }, "The largest stable timestep (None if even the finest is unstable).")
      .def("csv", &simloop::sweep_csv)
      .def("summary", &simloop::sweep_summary)
      .def(
          "write",
          [](const simloop::SweepResult& r, const std::filesystem::path& out) {
            simloop::prepare_output_dir(out);
            simloop::write_file_atomically(out / "sweep.csv", simloop::sweep_csv(r));
            return out / "sweep.csv";
          },
          "out"_a, "Writes sweep.csv into out (atomically); returns its path.");
  m.def(
      "sweep",
      [](const simloop::Model& model, const std::vector<double>& timesteps, double duration, int threads) {
        py::gil_scoped_release release;
        return simloop::sweep(model, timesteps, duration, threads);
      },
      "model"_a, "timesteps"_a, "duration"_a, "threads"_a);
  m.def("log_spaced", &simloop::log_spaced, "start"_a, "stop"_a, "count"_a);
  m.def("default_sweep_timesteps", &simloop::default_sweep_timesteps,
        "The default sweep's 25 round timesteps (1, 2, 3, 4, 5, 6, 8 per decade, 0.0005 s to 1 s).");
  m.attr("STABLE_HOP") = simloop::kStableHop;
  m.attr("STABLE_SINK") = simloop::kStableSink;
  m.attr("BOX_REST_Z") = simloop::kBoxRestZ;

  // The command line, parsed by the same code as sim_loop's.
  py::class_<simloop::cli::Options>(m, "CommandLine")
      .def_property_readonly("command", [](const simloop::cli::Options& o) {
        return o.command == simloop::cli::Command::kSweep ? "sweep" : "run";
      })
      .def_readonly("sweep_timesteps", &simloop::cli::Options::sweep_timesteps)
      .def_readonly("sweep_duration", &simloop::cli::Options::sweep_duration)
      .def_readonly("threads", &simloop::cli::Options::threads)
      .def_readonly("plot", &simloop::cli::Options::plot)
      .def_readonly("run", &simloop::cli::Options::run)
      .def_property_readonly("out", [](const simloop::cli::Options& o) { return o.out; })
      .def_readonly("model_path", &simloop::cli::Options::model_path)
      .def_readonly("rerun", &simloop::cli::Options::rerun)
      .def_readonly("help", &simloop::cli::Options::help)
      .def_readonly("version", &simloop::cli::Options::version);
  m.def("parse_command_line", [](const std::vector<std::string>& args) {
    std::vector<const char*> argv = {"simloop"};
    for (const std::string& a : args) argv.push_back(a.c_str());
    try {
      return simloop::cli::parse(static_cast<int>(argv.size()), argv.data());
    } catch (const simloop::cli::UsageError& e) {
      throw py::value_error(e.what());
    }
  });
  m.def("help_text", &simloop::cli::help_text, "program"_a, "recording"_a);
  m.def("sweep_help_text", &simloop::cli::sweep_help_text, "program"_a);
  m.def("prepare_output_dir", &simloop::prepare_output_dir, "dir"_a);
  m.def("write_file_atomically", [](const std::filesystem::path& path, const std::string& contents) {
    simloop::write_file_atomically(path, contents);
  }, "path"_a, "contents"_a);
}
