// simloop._core's Model: a compiled scene, its names and fixed facts,
// copies with other parameters, pickling, and what the recording draws.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "bindings_common.hpp"
#include "simloop/chapter_scene.hpp"
#include "simloop/fields.hpp"
#include "simloop/model.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"
#include "simloop/scenario_run.hpp"
#include "simloop/scene_geometry.hpp"
#include "simloop/scene_params.hpp"
#include "simloop/sim.hpp"

namespace simloop_py {

using namespace pybind11::literals;

namespace {

// Arguments taken as objects: pybind11's own TypeError for a wrong type lists every signature over four lines.
std::string kind_arg(const py::object& kind) { return std::string(check_text("kind", kind)); }

long long index_arg(const std::string& name, const py::object& value) {
  if (PyBool_Check(value.ptr()) || !PyIndex_Check(value.ptr())) {
    throw py::type_error(name + " must be an int, got " + describe(value));
  }
  PyObject* as_int = PyNumber_Index(value.ptr());
  if (as_int == nullptr) throw py::error_already_set();  // its __index__ raised
  const py::object index = py::reinterpret_steal<py::object>(as_int);
  int overflow = 0;
  const long long number = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
  if (overflow != 0) throw py::value_error(name + " must be an object's index, got " + show(value));
  return number;
}

}  // namespace

void bind_model(py::module_& m) {
  py::class_<simloop::Contact>(m, "Contact")
      .def_readonly("geom1", &simloop::Contact::geom1)
      .def_readonly("geom2", &simloop::Contact::geom2)
      .def_readonly("geom1_id", &simloop::Contact::geom1_id)
      .def_readonly("geom2_id", &simloop::Contact::geom2_id)
      .def_readonly("body1", &simloop::Contact::body1)
      .def_readonly("body2", &simloop::Contact::body2)
      .def_readonly("body1_id", &simloop::Contact::body1_id)
      .def_readonly("body2_id", &simloop::Contact::body2_id)
      .def_readonly("dist", &simloop::Contact::dist)
      .def_property_readonly("pos", [](const simloop::Contact& c) { return vec(c.pos.data(), 3); })
      .def_property_readonly("frame",
                             [](const simloop::Contact& c) {
                               py::array out = vec(c.frame.data(), 9);
                               return out.attr("reshape")(3, 3);
                             })
      .def_property_readonly("force", [](const simloop::Contact& c) { return vec(c.force.data(), 6); })
      .def("__repr__", [](const simloop::Contact& c) {
        return "Contact(" + c.geom1 + ", " + c.geom2 + ", dist=" + simloop::python_float_repr(c.dist) + ")";
      });

  py::class_<simloop::Model>(m, "Model", "A compiled MuJoCo world: read-only, shared by every run on it.")
      .def_static("pusher_scene", &simloop::pusher_scene, "The chapter's scene.")
      .def_static(
          "from_xml_string",
          [](const py::object& xml, const py::object& source) {
            const auto text = std::string(check_text("xml", xml));
            const auto name = std::string(check_text("source", source));
            return naming_failures("Model.from_xml_string",
                                   [&] { return simloop::Model::from_xml_string(text, name); });
          },
          "xml"_a, "source"_a = "<string>",
          "Compiles MJCF text (str or UTF-8 bytes); source names it in errors. simloop.MujocoError if MuJoCo "
          "rejects it.")
      .def_static(
          "from_file",
          [](const py::object& given) {
            const std::filesystem::path path = path_arg("path", given, "an MJCF file");
            return naming_failures("Model.from_file(" + path.string() + ")",
                                   [&] { return simloop::Model::from_file(path.string()); });
          },
          "path"_a, "Compiles an MJCF file: OSError if it cannot be read, simloop.MujocoError if MuJoCo rejects it.")
      .def_static(
          "_copy_of_address",
          [](std::uintptr_t address, std::string_view source) {
            // simloop.load_model checked that the address is a mujoco.MjModel's
            // of this very libmujoco (simloop/_mujoco_check.py).
            return simloop::Model::copy_of(reinterpret_cast<const mjModel*>(address), source);
          },
          "address"_a, "source"_a, "A copy of the mjModel at `address` (a mujoco.MjModel's _address).")
      .def(
          "with_timestep",
          [](const simloop::Model& model, const py::object& timestep) {
            return model.with_timestep(check_real("timestep", timestep));
          },
          "timestep"_a, "A copy with opt.timestep set (a positive, finite number).")
      .def_property_readonly("timestep", &simloop::Model::timestep)
      .def_property_readonly("nq", [](const simloop::Model& model) { return model.get()->nq; })
      .def_property_readonly("nv", [](const simloop::Model& model) { return model.get()->nv; })
      .def_property_readonly("nu", [](const simloop::Model& model) { return model.get()->nu; })
      .def("__repr__",
           [](const simloop::Model& model) {
             const mjModel* raw = model.get();
             const std::string name = model.name();
             return "<simloop.Model " + (name.empty() ? std::string("(unnamed)") : "'" + name + "'") +
                    " nq=" + std::to_string(raw->nq) + " nv=" + std::to_string(raw->nv) +
                    " nu=" + std::to_string(raw->nu) + " nbody=" + std::to_string(raw->nbody) +
                    " timestep=" + simloop::python_float_repr(model.timestep()) + ">";
           })
      .def_property_readonly("name", &simloop::Model::name, "<mujoco model=...>'s name ('' if none).")
      .def_property_readonly("load_warnings", &simloop::Model::load_warnings,
                             "What MuJoCo warned while it parsed and compiled the scene, a line each.")
      .def_property_readonly(
          "has_chapter_layout",
          [](const simloop::Model& model) { return simloop::chapter_layout_missing(model).empty(); },
          "True if the scene has the chapter's box and pusher (the chapter's loop runs on it).")
      .def_property_readonly(
          "chapter_layout",
          [](const simloop::Model& model) {
            const simloop::ChapterLayout at = simloop::chapter_layout(model);  // ValueError naming what the scene lacks
            return py::dict("box_body"_a = at.box_body, "box_qposadr"_a = at.box_qposadr,
                            "box_dofadr"_a = at.box_dofadr, "pusher_qposadr"_a = at.pusher_qposadr,
                            "pusher_dofadr"_a = at.pusher_dofadr);
          },
          "Where the chapter's box and pusher are (body id, qpos and qvel addresses).")
      .def_property_readonly("nbody", [](const simloop::Model& model) { return model.get()->nbody; })
      .def_property_readonly("njnt", [](const simloop::Model& model) { return model.get()->njnt; })
      .def_property_readonly("na", [](const simloop::Model& model) { return model.get()->na; })
      .def_property_readonly("nsensor", [](const simloop::Model& model) { return model.get()->nsensor; })
      .def_property_readonly("nsensordata", [](const simloop::Model& model) { return model.get()->nsensordata; })
      .def_property_readonly("nkey", [](const simloop::Model& model) { return model.get()->nkey; })
      .def(
          "names",
          [](const simloop::Model& model, const py::object& kind) {
            return simloop::object_names(model.get(), simloop::object_type_of_kind(kind_arg(kind)));
          },
          "kind"_a, "Every object's name of a kind, by index ('' for an unnamed one).")
      .def(
          "object_info",
          [](const simloop::Model& model, const py::object& kind, const py::object& index) {
            // The model's fixed facts the named views need, as plain values.
            const mjModel* raw = model.get();
            const mjtObj type = simloop::object_type_of_kind(kind_arg(kind));
            const int id = simloop::checked_object_index(raw, type, index_arg("id", index));
            if (type == mjOBJ_BODY) {
              return py::dict("mass"_a = raw->body_mass[id], "mocapid"_a = raw->body_mocapid[id]);
            }
            if (type == mjOBJ_JOINT) {
              const simloop::JointSize size = simloop::joint_size(raw->jnt_type[id]);
              return py::dict("type"_a = simloop::joint_type_name(raw->jnt_type[id]),
                              "qposadr"_a = raw->jnt_qposadr[id], "nq"_a = size.nq, "dofadr"_a = raw->jnt_dofadr[id],
                              "nv"_a = size.nv, "body"_a = raw->jnt_bodyid[id]);
            }
            if (type == mjOBJ_ACTUATOR) {
              return py::dict(
                  "ctrlrange"_a = py::make_tuple(raw->actuator_ctrlrange[2 * id], raw->actuator_ctrlrange[2 * id + 1]),
                  "ctrllimited"_a = raw->actuator_ctrllimited[id] != 0,
                  "joint"_a = raw->actuator_trntype[id] == mjTRN_JOINT ? raw->actuator_trnid[2 * id] : -1);
            }
            if (type == mjOBJ_SENSOR) {
              return py::dict("adr"_a = raw->sensor_adr[id], "dim"_a = raw->sensor_dim[id]);
            }
            return py::dict();
          },
          "kind"_a, "id"_a)
      .def(py::pickle([](const simloop::Model& model) { return py::bytes(model.to_bytes()); },
                      [](const py::bytes& bytes) { return simloop::Model::from_bytes(std::string(bytes)); }));
  m.def(
      "scene_geometry",
      [](const simloop::Model& model) {
        static constexpr const char* kKinds[] = {"plane",    "sphere", "capsule", "ellipsoid",
                                                 "cylinder", "box",    "mesh",    "other"};
        py::list out;
        for (const simloop::GeomShape& g : simloop::scene_geometry(model.get())) {
          out.append(py::dict("name"_a = g.name, "body"_a = g.body, "body_id"_a = g.body_id,
                              "kind"_a = kKinds[static_cast<int>(g.kind)], "half_size"_a = vec(g.half_size.data(), 3),
                              "mesh_center"_a = vec(g.mesh_center.data(), 3), "pos"_a = vec(g.pos.data(), 3),
                              "quat"_a = vec(g.quat.data(), 4),
                              "rgba"_a = py::make_tuple(g.rgba[0], g.rgba[1], g.rgba[2], g.rgba[3])));
        }
        return out;
      },
      "model"_a, "Every visible geom: its shape, its pose on its body, its colour.");
  m.def("pusher_track", [](const simloop::Model& model) {
    const simloop::PusherTrack t = simloop::pusher_track(model);
    return py::make_tuple(vec(t.rest_position.data(), 3), vec(t.axis.data(), 3), t.q0);
  });
  m.def(
      "with_scene_params",
      [](const simloop::Model& model, const std::vector<std::tuple<std::string, std::string, double>>& params) {
        std::vector<simloop::SceneParam> converted;
        for (const auto& [kind, name, value] : params) {
          simloop::SceneParam p;
          p.kind = simloop::scene_param_kind(kind);
          p.name = name;
          p.value = value;
          converted.push_back(p);
        }
        return simloop::with_scene_params(model, converted);
      },
      "model"_a, "params"_a, "A copy of model with (kind, name, value) scene parameters applied.");
  m.def(
      "scene_param_column",
      [](const std::string& kind, const std::string& name, const std::string& field, int index) {
        return simloop::scene_param_column({simloop::scene_param_kind(kind), name, 0.0, field, index});
      },
      "kind"_a, "name"_a, "field"_a = "", "index"_a = 0,
      "The column a scene parameter's value is shown under: friction, mass_box, geom_friction_box_0, ...");
  m.def("moving_bodies", &simloop::moving_bodies, "scene"_a);
  m.attr("MODEL_FIELD_NAMES") = py::tuple(py::cast(simloop::model_field_names()));
  m.attr("DATA_FIELD_NAMES") = py::tuple(py::cast(simloop::data_field_names()));
  m.attr("OBJECT_KINDS") = py::tuple(py::cast(simloop::object_kinds()));
  m.attr("WRITABLE_MODEL_FIELDS") = py::tuple(py::cast(simloop::writable_model_field_names()));
  m.attr("NONNEGATIVE_MODEL_FIELDS") = py::tuple(py::cast(simloop::nonnegative_model_field_names()));
}

}  // namespace simloop_py
