// Scene parameters varied per run: the same scene with another friction,
// mass or damping, or any value of a writable mjModel array (a geom's size
// row, an actuator's gain), as a robustness study sweeps them. Each is applied to a
// copy of the compiled model (the original stays shared and untouched); the
// timestep is not here because RunConfig / ScenarioConfig already carry it.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "simloop/model.hpp"

namespace simloop {

struct SceneParam {
  enum class Kind {
    kFriction,  // geom_friction's sliding coefficient (the first of three) of a geom, or of every geom
    kMass,      // body_mass of a body, its inertia scaled by the same factor (the shape's density changes)
    kDamping,   // dof_damping of every degree of freedom of a joint, or of every joint
    kGravity,   // the strength of opt.gravity (m/s^2), its direction kept (-z if it was 0); no name
    kModel,     // value `index` of the row of `name` in mjModel's array `field` (fields.hpp's writable ones)
  };
  Kind kind = Kind::kFriction;
  // The geom, body or joint: its name, or the digits of its index where no
  // object has that name (an unnamed one); "" for every geom / joint (not
  // allowed for a mass).
  std::string name;
  double value = 0.0;  // friction >= 0; mass > 0 (kg); damping >= 0 (N s/m or N m s/rad)
  // kModel only: the array ("geom_friction") and the value's place in a row
  // (0 to the array's columns - 1). Its name is the row's object (a geom of
  // geom_*, a body of body_*, ...), "" for every row (every body but the
  // world). Values are written as they are, a float array's rounded to float
  // when drawn; masses, inertias and armatures then recompute MuJoCo's
  // constants (mj_setConst), as a mass does. Finite; >= 0 for masses,
  // inertias, frictions, margins, colours, dampings, armatures, friction
  // losses and stiffnesses.
  std::string field;
  int index = 0;
};

// "friction", "mass", "damping", "gravity", "model".
[[nodiscard]] const char* scene_param_kind_name(SceneParam::Kind kind) noexcept;
// The kind of that name; InvalidArgument listing the kinds otherwise.
[[nodiscard]] SceneParam::Kind scene_param_kind(std::string_view name);

// The column a drawn or swept value is shown under (a batch's table, an
// env's info): its kind, then "_<name>" when it names one (friction,
// friction_box, mass_box, gravity); a model value: "<field>_<name>", then
// "_<index>" when the array's rows hold more than one value
// (body_mass_box, geom_friction_box_0, geom_rgba_3 for every geom).
[[nodiscard]] std::string scene_param_column(const SceneParam& param);

// A copy of `model` with every param applied in order (a later one on the
// same thing wins). A mass scales the body's inertia by new/old mass (so its
// principal axes and radii of gyration stay), updates the subtree masses of
// it and its ancestors by the difference, and recomputes MuJoCo's constants
// (mj_setConst: the inverse weights the contact solver scales by). A value
// equal to the scene's own gives a model whose runs are bitwise those of the
// original. Throws InvalidArgument naming the param: an unknown name (with
// a did-you-mean and what the scene has), a value that is not finite or is
// out of range, a mass for the world body or for a body whose mass is 0.
[[nodiscard]] Model with_scene_params(const Model& model, const std::vector<SceneParam>& params);

// Throws what with_scene_params(model, {param}) would (a name the scene
// lacks, a value out of range), without copying the model.
void check_scene_param(const mjModel* m, const SceneParam& param);

}  // namespace simloop
