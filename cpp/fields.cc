#include "simloop/fields.hpp"

#include <mujoco/mjxmacro.h>

#include <algorithm>
#include <array>
#include <string>
#include <type_traits>

#include "mujoco_compat.hpp"
#include "simloop/errors.hpp"
#include "simloop/object_names.hpp"

namespace simloop {
namespace {

using detail::compat::RawArray;

FieldView view_of(const RawArray& a) {
  return FieldView{a.data, a.element, a.rows, a.cols, object_type_counted_by(a.rows_count), std::string(a.rows_count)};
}

std::vector<std::string> names_of(bool (*each)(const std::function<bool(const RawArray&)>&)) {
  std::vector<std::string> names;
  each([&](const RawArray& a) {
    names.emplace_back(a.name);
    return false;
  });
  return names;
}

[[noreturn]] void no_such(const char* owner, std::string_view name, const std::vector<std::string>& names) {
  const std::string hint = did_you_mean(std::string(name), names);
  throw InvalidArgument(std::string("no ") + owner + " array named '" + std::string(name) + "'" +
                        (hint.empty() ? "" : " (did you mean '" + hint + "'?)"));
}

// A scene to list the names from: the arrays are the same for every scene.
const mjModel* any_model() {
  static mjModel empty{};
  return &empty;
}

template <class T>
DataNumbers numbers_only(T* mjData::*member) noexcept {
  if constexpr (std::is_same_v<T, mjtNum>) {
    return member;
  } else {
    return nullptr;
  }
}

}  // namespace

DataNumbers data_numbers(std::string_view name) noexcept {
#define X(type, array, rows, cols) \
  if (name == #array) return numbers_only(&mjData::array);
#define XNV X
  MJDATA_POINTERS
#undef XNV
#undef X
  return nullptr;
}

const std::vector<std::string>& model_field_names() {
  static const std::vector<std::string> names = names_of([](const std::function<bool(const RawArray&)>& visit) {
    return detail::compat::each_model_array(any_model(), visit);
  });
  return names;
}

const std::vector<std::string>& data_field_names() {
  static const std::vector<std::string> names = names_of([](const std::function<bool(const RawArray&)>& visit) {
    static mjData empty{};
    return detail::compat::each_data_array(any_model(), &empty, visit);
  });
  return names;
}

FieldView model_field(const mjModel* m, std::string_view name) {
  FieldView found;
  if (detail::compat::each_model_array(m, [&](const RawArray& a) {
        if (a.name != name) return false;
        found = view_of(a);
        return true;
      })) {
    return found;
  }
  no_such("mjModel", name, model_field_names());
}

FieldView model_field_layout(std::string_view name) { return model_field(any_model(), name); }

FieldView data_field(const mjModel* m, const mjData* d, std::string_view name) {
  FieldView found;
  if (detail::compat::each_data_array(m, d, [&](const RawArray& a) {
        if (a.name != name) return false;
        found = view_of(a);
        return true;
      })) {
    return found;
  }
  if (name == "contact") {
    throw InvalidArgument(
        "mjData's contact array holds structs, not numbers: read a Sim's contacts (with their "
        "forces) instead");
  }
  no_such("mjData", name, data_field_names());
}

bool filled_after_constraint(std::string_view name) noexcept {
  return name == "cacc" || name == "cfrc_int" || name == "cfrc_ext";
}

bool filled_on_request(std::string_view name) noexcept {
  return filled_after_constraint(name) || name == "subtree_linvel" || name == "subtree_angmom";
}

void fill_derived(const mjModel* m, mjData* d, std::string_view name) noexcept {
  if (filled_after_constraint(name)) {
    mj_rnePostConstraint(m, d);
  } else if (filled_on_request(name)) {
    mj_subtreeVel(m, d);
  }
}

std::vector<std::string> writable_model_field_names() {
  std::vector<std::string> names;
  for (const std::string& name : model_field_names()) {
    if (model_field_writable(name)) names.push_back(name);
  }
  return names;
}

bool model_field_writable(std::string_view name) noexcept {
  static constexpr std::array<std::string_view, 19> kWritable{
      "body_mass",          "body_inertia",        "body_gravcomp",    "geom_friction",    "geom_solref",
      "geom_solimp",        "geom_margin",         "geom_rgba",        "dof_damping",      "dof_armature",
      "dof_frictionloss",   "jnt_stiffness",       "actuator_gear",    "actuator_gainprm", "actuator_biasprm",
      "actuator_ctrlrange", "actuator_forcerange", "tendon_stiffness", "tendon_damping"};
  return std::find(kWritable.begin(), kWritable.end(), name) != kWritable.end();
}

std::vector<std::string> nonnegative_model_field_names() {
  std::vector<std::string> names = writable_model_field_names();
  names.erase(
      std::remove_if(names.begin(), names.end(), [](const std::string& n) { return !model_field_nonnegative(n); }),
      names.end());
  return names;
}

bool model_field_nonnegative(std::string_view name) noexcept {
  static constexpr std::array<std::string_view, 11> kNonnegative{
      "body_mass",    "body_inertia",     "geom_friction", "geom_margin",      "geom_rgba",     "dof_damping",
      "dof_armature", "dof_frictionloss", "jnt_stiffness", "tendon_stiffness", "tendon_damping"};
  return std::find(kNonnegative.begin(), kNonnegative.end(), name) != kNonnegative.end();
}

}  // namespace simloop
