// Scene parameters varied per run: the same scene with another friction,
// mass or damping, as a robustness study sweeps them. Each is applied to a
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
  };
  Kind kind = Kind::kFriction;
  std::string name;    // the geom, body or joint; "" for every geom / joint (not allowed for a mass)
  double value = 0.0;  // friction >= 0; mass > 0 (kg); damping >= 0 (N s/m or N m s/rad)
};

// "friction", "mass", "damping", "gravity".
[[nodiscard]] const char* scene_param_kind_name(SceneParam::Kind kind) noexcept;
// The kind of that name; InvalidArgument listing the kinds otherwise.
[[nodiscard]] SceneParam::Kind scene_param_kind(std::string_view name);

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
