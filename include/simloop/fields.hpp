// Every array of MuJoCo's mjModel and mjData by its name ("geom_friction",
// "xpos", "efc_force"), as MuJoCo's own mjxmacro.h lists them for the
// version we are built on: where it is, its element type, its rows and
// columns, and which kind of object a row is (so that rows can be named,
// as dm_control's physics.named does).
#pragma once

#include <mujoco/mujoco.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace simloop {

enum class Element { kFloat64, kFloat32, kInt32, kInt64, kUInt64, kUInt8, kInt8 };

struct FieldView {
  void* data = nullptr;
  Element element = Element::kFloat64;
  long long rows = 0;
  long long cols = 0;
  // What a row is: the object type (mjOBJ_BODY for "nbody" rows, ...),
  // mjOBJ_UNKNOWN when rows are not objects (nq, nv, nefc, ...).
  mjtObj rows_are = mjOBJ_UNKNOWN;
  std::string rows_count;  // the size that counts the rows: "nbody", "nv", "nefc", ...
};

// The arrays this MuJoCo's mjModel and mjData have, by name.
[[nodiscard]] const std::vector<std::string>& model_field_names();
[[nodiscard]] const std::vector<std::string>& data_field_names();

// mjModel's array `name` of `m`. Throws InvalidArgument naming a likely
// typo's fix ("no mjModel array named 'geom_fricton' (did you mean
// 'geom_friction'?)").
[[nodiscard]] FieldView model_field(const mjModel* m, std::string_view name);
// The same without a model: its element type, columns and what a row is
// (data null, rows 0).
[[nodiscard]] FieldView model_field_layout(std::string_view name);
// mjData's array `name` of `d`: the contacts' and constraints' arrays with
// the rows in use now (ncon, nefc), valid until the next step. Throws
// InvalidArgument as model_field does, and for the contact structs
// ("contact": see Sim::contacts).
[[nodiscard]] FieldView data_field(const mjModel* m, const mjData* d, std::string_view name);

// mjData's array of numbers `name` as a member (d->*member), for reading
// it in a loop without looking it up: nullptr if mjData has none of that
// name or its elements are not mjtNum.
using DataNumbers = mjtNum* mjData::*;
[[nodiscard]] DataNumbers data_numbers(std::string_view name) noexcept;

// Whether mjData's array `name` is one MuJoCo fills only in
// mj_rnePostConstraint (cacc, cfrc_int, cfrc_ext), which no step calls:
// read without it, they hold zeros or an older state's values.
[[nodiscard]] bool filled_after_constraint(std::string_view name) noexcept;
// Whether it is one MuJoCo fills only on request, which no step does:
// those above, and subtree_linvel, subtree_angmom (mj_subtreeVel).
[[nodiscard]] bool filled_on_request(std::string_view name) noexcept;
// Fills mjData's array `name` on `d` if MuJoCo fills it only on request
// (mj_rnePostConstraint or mj_subtreeVel), for the state d's derived
// quantities describe (after a step, the state it started from, as
// Gymnasium's MujocoEnv reads them); else does nothing. Changes nothing a
// step reads. The one place every read of such an array (a named read, a
// recorded column, a hook's view) fills it, where it is read, not every
// step. Calls MuJoCo unguarded: call it inside MuJoCo's error guard.
void fill_derived(const mjModel* m, mjData* d, std::string_view name) noexcept;

// The model parameters a trainer randomises, which a Sim lets a caller
// write (in its own copy of the model): masses and inertias, friction,
// contact softness, damping, armature, joint stiffness, actuator gains,
// biases, gears and ranges, colours.
[[nodiscard]] bool model_field_writable(std::string_view name) noexcept;
// Those of model_field_names() that are writable, in its order.
[[nodiscard]] std::vector<std::string> writable_model_field_names();
// Writable arrays whose negative values mean nothing physical (masses,
// inertias, frictions, margins, colours, dampings, armatures, friction
// losses, stiffnesses): refused below 0 wherever they are written (a
// scene parameter, a Sim's named model view).
[[nodiscard]] bool model_field_nonnegative(std::string_view name) noexcept;
// Those of writable_model_field_names() that are, in its order.
[[nodiscard]] std::vector<std::string> nonnegative_model_field_names();

}  // namespace simloop
