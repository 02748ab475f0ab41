// A scene's objects by name or index, with errors that say what the scene
// has: the one lookup Sim, the renderer's cameras and bodies share.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <mujoco/mujoco.h>

namespace simloop {

// The id of the model's object of `type` named `name`. Throws
// InvalidArgument naming what the scene has, with a likely typo's fix:
// "no body named 'torsoo' (did you mean 'torso'?); the scene's bodies: ...".
// Types looked up: those object_kinds() names (InvalidArgument for others).
[[nodiscard]] int object_id(const mjModel* m, mjtObj type, const std::string& name);

// The object type a kind's word names ("body", "geom", "site", "camera",
// "tendon", "keyframe", ...), mjOBJ_UNKNOWN for another word; the words, in
// MuJoCo's order of types; a type's word; how many the scene has.
[[nodiscard]] mjtObj object_type_named(std::string_view kind) noexcept;
[[nodiscard]] const std::vector<std::string>& object_kinds();
[[nodiscard]] const char* object_kind(mjtObj type);
[[nodiscard]] int object_count(const mjModel* m, mjtObj type);
// Every object's name of a type, by id ("" for an unnamed one).
[[nodiscard]] std::vector<std::string> object_names(const mjModel* m, mjtObj type);
// The kind an mjModel size counts ("ngeom": geoms, "nu": actuators),
// mjOBJ_UNKNOWN for a size that counts no kind of object (nq, nv, nefc, ...).
[[nodiscard]] mjtObj object_type_counted_by(std::string_view size) noexcept;

// The same for an index: throws InvalidArgument unless 0 <= index < count.
[[nodiscard]] int checked_object_index(const mjModel* m, mjtObj type, long long index);

// How many qpos and qvel values a joint of MuJoCo's type `type` has: free
// 7 and 6, ball 4 and 3, slide and hinge 1 and 1; and the type's word.
struct JointSize {
  int nq;
  int nv;
};
[[nodiscard]] JointSize joint_size(int type) noexcept;
[[nodiscard]] const char* joint_type_name(int type) noexcept;

}  // namespace simloop
