#include "simloop/scene_params.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "mujoco_compat.hpp"
#include "mujoco_guard.hpp"
#include "simloop/errors.hpp"
#include "simloop/fields.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"
#include "simloop/scenario.hpp"

namespace simloop {
namespace {

std::string describe(const SceneParam& p) {
  const std::string what = p.kind == SceneParam::Kind::kModel ? p.field + "[" + std::to_string(p.index) + "]"
                                                              : std::string(scene_param_kind_name(p.kind));
  return what + (p.name.empty() ? "" : " of '" + p.name + "'") + " = " + python_float_repr(p.value);
}

// The object `p` names, by name or (an unnamed one) by index, as a
// scenario names objects; or InvalidArgument saying what the scene has.
int find_named(const mjModel* m, mjtObj type, const SceneParam& p) {
  try {
    return object_id_or_index(m, type, p.name);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(describe(p) + ": " + e.what());
  }
}

void check_value(const SceneParam& p) {
  const bool positive_only = p.kind == SceneParam::Kind::kMass;
  if (!std::isfinite(p.value) || p.value < 0.0 || (positive_only && p.value == 0.0)) {
    throw InvalidArgument(describe(p) + ": " + scene_param_kind_name(p.kind) + " must be a finite number " +
                          (positive_only ? "> 0" : ">= 0"));
  }
}

// Model arrays that mj_setConst derives constants from (the inverse
// weights, dof_M0, the subtree masses).
bool feeds_constants(std::string_view field) {
  return field == "body_mass" || field == "body_inertia" || field == "dof_armature";
}

// A kModel param: checks it against `scene`, then (with `m`) writes it.
bool apply_model_field(const mjModel* scene, mjModel* m, const SceneParam& p) {
  if (p.field.empty()) throw InvalidArgument(describe(p) + ": a model value needs a field (an mjModel array's name)");
  FieldView layout;
  try {
    layout = model_field(scene, p.field);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(describe(p) + ": " + e.what());  // with a did-you-mean
  }
  if (!model_field_writable(p.field)) {
    std::string list;
    for (const std::string& name : writable_model_field_names()) list += (list.empty() ? "" : ", ") + name;
    throw InvalidArgument(describe(p) + ": mjModel's " + p.field + " is not one a run may vary; these are: " + list);
  }
  if (p.index < 0 || p.index >= layout.cols) {
    throw InvalidArgument(describe(p) + ": index must be 0 to " + std::to_string(layout.cols - 1) + " (" + p.field +
                          " holds " + std::to_string(layout.cols) + " value" + (layout.cols == 1 ? "" : "s") +
                          " per row)");
  }
  if (!std::isfinite(p.value) || (model_field_nonnegative(p.field) && p.value < 0.0)) {
    throw InvalidArgument(describe(p) + ": " + p.field + " must be a finite number" +
                          (model_field_nonnegative(p.field) ? " >= 0" : ""));
  }
  // The rows: the named object's (a dof_ array's: its joint's degrees of
  // freedom, as a damping's), or every row (every body but the world).
  const bool of_dofs = layout.rows_count == "nv";
  const int named = p.name.empty() ? -1 : find_named(scene, of_dofs ? mjOBJ_JOINT : layout.rows_are, p);
  std::vector<long long> rows;
  for (long long row = named < 0 && layout.rows_are == mjOBJ_BODY ? 1 : 0; row < layout.rows; ++row) {
    if (named < 0 || (of_dofs ? scene->dof_jntid[row] == named : row == named)) rows.push_back(row);
  }
  if (m == nullptr) return false;
  const FieldView target = model_field(m, p.field);
  for (const long long row : rows) {
    const long long at = row * target.cols + p.index;
    if (target.element == Element::kFloat32) {
      static_cast<float*>(target.data)[at] = static_cast<float>(p.value);
    } else {
      static_cast<mjtNum*>(target.data)[at] = p.value;
    }
  }
  return feeds_constants(p.field);
}

// Applies `p` to `m` (with `m` null: only checks it against `scene`).
// Returns true if the constants mj_setConst derives from the masses must be
// recomputed.
bool apply(const mjModel* scene, mjModel* m, const SceneParam& p) {
  if (p.kind == SceneParam::Kind::kModel) return apply_model_field(scene, m, p);
  check_value(p);
  switch (p.kind) {
    case SceneParam::Kind::kFriction: {
      const int first = p.name.empty() ? 0 : find_named(scene, mjOBJ_GEOM, p);
      const int end = p.name.empty() ? detail::compat::as_int(scene->ngeom) : first + 1;
      if (m == nullptr) return false;
      for (int g = first; g < end; ++g) m->geom_friction[3 * g] = p.value;
      return false;
    }
    case SceneParam::Kind::kDamping: {
      const int first = p.name.empty() ? 0 : find_named(scene, mjOBJ_JOINT, p);
      const int end = p.name.empty() ? detail::compat::as_int(scene->njnt) : first + 1;
      if (m == nullptr) return false;
      for (int j = first; j < end; ++j) {
        for (int v = 0; v < m->nv; ++v) {
          if (m->dof_jntid[v] == j) m->dof_damping[v] = p.value;
        }
      }
      return false;
    }
    case SceneParam::Kind::kMass: {
      if (p.name.empty()) throw InvalidArgument(describe(p) + ": a mass needs a body's name");
      const int body = find_named(scene, mjOBJ_BODY, p);
      if (body == 0) throw InvalidArgument(describe(p) + ": the world body has no mass to set");
      const double old_mass = scene->body_mass[body];
      if (!(old_mass > 0.0)) {
        throw InvalidArgument(describe(p) + ": body '" + p.name +
                              "' has no mass in the scene, so there is no inertia to scale");
      }
      if (m == nullptr) return false;
      // Same shape, another density: the inertia scales with the mass. An
      // unchanged mass is a factor of exactly 1 and a difference of exactly 0.
      const double factor = p.value / old_mass;
      const double difference = p.value - old_mass;
      m->body_mass[body] = p.value;
      for (int k = 0; k < 3; ++k) m->body_inertia[3 * body + k] *= factor;
      for (int b = body; b > 0; b = m->body_parentid[b]) m->body_subtreemass[b] += difference;
      m->body_subtreemass[0] += difference;
      return true;
    }
    case SceneParam::Kind::kGravity: {
      if (!p.name.empty()) throw InvalidArgument(describe(p) + ": gravity is the whole scene's: give no name");
      if (m == nullptr) return false;
      const double norm = std::sqrt(m->opt.gravity[0] * m->opt.gravity[0] + m->opt.gravity[1] * m->opt.gravity[1] +
                                    m->opt.gravity[2] * m->opt.gravity[2]);
      if (norm == 0.0) {
        m->opt.gravity[0] = m->opt.gravity[1] = 0.0;
        m->opt.gravity[2] = -p.value;
      } else {
        for (int k = 0; k < 3; ++k) m->opt.gravity[k] *= p.value / norm;
      }
      return false;
    }
    case SceneParam::Kind::kModel:
      break;  // above
  }
  return false;
}

constexpr SceneParam::Kind kKinds[] = {SceneParam::Kind::kFriction, SceneParam::Kind::kMass, SceneParam::Kind::kDamping,
                                       SceneParam::Kind::kGravity, SceneParam::Kind::kModel};

}  // namespace

const char* scene_param_kind_name(SceneParam::Kind kind) noexcept {
  switch (kind) {
    case SceneParam::Kind::kFriction:
      return "friction";
    case SceneParam::Kind::kMass:
      return "mass";
    case SceneParam::Kind::kDamping:
      return "damping";
    case SceneParam::Kind::kGravity:
      return "gravity";
    case SceneParam::Kind::kModel:
      return "model";
  }
  return "?";
}

SceneParam::Kind scene_param_kind(std::string_view name) {
  std::string list;
  for (const SceneParam::Kind kind : kKinds) {
    if (name == scene_param_kind_name(kind)) return kind;
    list += (list.empty() ? "'" : ", '") + std::string(scene_param_kind_name(kind)) + "'";
  }
  throw InvalidArgument("scene parameter kind must be one of " + list + ", got '" + std::string(name) + "'");
}

std::string scene_param_column(const SceneParam& p) {
  if (p.kind != SceneParam::Kind::kModel) {
    const std::string kind = scene_param_kind_name(p.kind);
    return p.name.empty() ? kind : kind + "_" + p.name;
  }
  const bool one_per_row = model_field_layout(p.field).cols == 1;
  return p.field + (p.name.empty() ? "" : "_" + p.name) + (one_per_row ? "" : "_" + std::to_string(p.index));
}

void check_scene_param(const mjModel* m, const SceneParam& param) { (void)apply(m, nullptr, param); }

Model with_scene_params(const Model& model, const std::vector<SceneParam>& params) {
  if (params.empty()) return model;
  // A fresh copy of the model that nothing else holds yet: ours to edit
  // before it is shared (as Model::for_run edits its copy). Each param is
  // checked as it is written (apply), once: on a bad one the copy is dropped.
  Model copy = model.with_timestep(model.timestep());
  mjModel* m = const_cast<mjModel*>(copy.get());
  bool masses_changed = false;
  for (const SceneParam& p : params) masses_changed = apply(m, m, p) || masses_changed;
  if (masses_changed) {
    mjData* d = nullptr;
    try {
      detail::mujoco_call([&] { d = mj_makeData(m); });
      detail::mujoco_call([&] { mj_setConst(m, d); });
    } catch (const MujocoError& e) {
      if (d != nullptr) mj_deleteData(d);
      throw MujocoError(std::string("recomputing the model's constants after a mass change: ") + e.what());
    }
    mj_deleteData(d);
  }
  return copy;
}

}  // namespace simloop
