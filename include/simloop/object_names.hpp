// A scene's objects by name or index, with errors that say what the scene
// has: the one lookup Sim, the renderer's cameras and bodies share.
#pragma once

#include <mujoco/mujoco.h>

#include <string>
#include <string_view>
#include <vector>

namespace simloop {

// The id of the model's object of `type` named `name`. Throws
// InvalidArgument naming what the scene has, with a likely typo's fix:
// "no body named 'torsoo' (did you mean 'torso'?); the scene's bodies: ...".
// Types looked up: those object_kinds() names (InvalidArgument for others).
[[nodiscard]] int object_id(const mjModel* m, mjtObj type, const std::string& name);
// The same without the error: -1 if no object of `type` has that name. An
// empty name names none (MuJoCo's own lookup of "" finds the first unnamed
// object): the one place every lookup by name goes through.
[[nodiscard]] int named_object_id(const mjModel* m, mjtObj type, const std::string& name) noexcept;

// The object type a kind's word names ("body", "geom", "site", "camera",
// "tendon", "keyframe", ...), mjOBJ_UNKNOWN for another word; the words, in
// MuJoCo's order of types; a type's word; how many the scene has.
[[nodiscard]] mjtObj object_type_named(std::string_view kind) noexcept;
// The same, or InvalidArgument "kind must be one of 'body', ..., got '...'".
[[nodiscard]] mjtObj object_type_of_kind(std::string_view kind);
[[nodiscard]] const std::vector<std::string>& object_kinds();
[[nodiscard]] const char* object_kind(mjtObj type);
[[nodiscard]] int object_count(const mjModel* m, mjtObj type);
// Every object's name of a type, by id ("" for an unnamed one).
[[nodiscard]] std::vector<std::string> object_names(const mjModel* m, mjtObj type);

// One object's name, or its kind and index where the scene left it unnamed
// ("body3", "joint0"): how columns, recordings and reports name it.
[[nodiscard]] std::string object_name(const mjModel* m, mjtObj type, int id);
// The kind an mjModel size counts ("ngeom": geoms, "nu": actuators),
// mjOBJ_UNKNOWN for a size that counts no kind of object (nq, nv, nefc, ...).
[[nodiscard]] mjtObj object_type_counted_by(std::string_view size) noexcept;

// The same for an index: throws InvalidArgument unless 0 <= index < count.
[[nodiscard]] int checked_object_index(const mjModel* m, mjtObj type, long long index);

// Whether a body can move: it is not welded to the world (it, or a body it
// is fixed to, has a joint or is a mocap body). And whether a force on it
// moves anything: the body it is fixed to has joints (a mocap body moves
// only where mocap_pos puts it).
[[nodiscard]] bool body_can_move(const mjModel* m, int body);
[[nodiscard]] bool body_can_be_pushed(const mjModel* m, int body);

// Which objects of a kind a lookup may name, for its error's listing: all
// (no `keep`), or those `keep` passes, called `what` ("bodies that can move").
struct ObjectFilter {
  const char* what = nullptr;
  bool (*keep)(const mjModel*, int) = nullptr;
};

// What a lookup could have named: "the scene's joints: hip, knee; unnamed,
// by index: 0, 3 to 5", or "the scene has no joints".
[[nodiscard]] std::string object_listing(const mjModel* m, mjtObj type, ObjectFilter listed = {});

// Every lookup's error, one wording: "no body named 'torsoo' (did you mean
// 'torso'?); the scene's bodies: world, torso; unnamed, by index: 3 to 5",
// and "body index 9 is out of range: the scene has 6 bodies (0 to 5); the
// scene's bodies: ...". The hint is drawn from every name of the kind.
[[nodiscard]] std::string unknown_name_message(const mjModel* m, mjtObj type, const std::string& name,
                                               ObjectFilter listed = {});
[[nodiscard]] std::string index_out_of_range_message(const mjModel* m, mjtObj type, const std::string& index,
                                                     ObjectFilter listed = {});

// How a scenario names an object: by its name, or, where no object has that
// name and `name` is digits, by its index (an unnamed object: Gymnasium's
// actuators, say). Throws InvalidArgument with unknown_name_message or
// index_out_of_range_message, listing what `listed` passes.
[[nodiscard]] int object_id_or_index(const mjModel* m, mjtObj type, const std::string& name, ObjectFilter listed = {});
// Whether `name` is an index's text (digits only), as object_id_or_index reads it.
[[nodiscard]] bool is_index_text(std::string_view name) noexcept;

// The likely typo's fix among `candidates` ("" if none is close): case
// aside, at most a third of the longer name's edits away (at least one).
[[nodiscard]] std::string did_you_mean(std::string_view name, const std::vector<std::string>& candidates);

// How many qpos and qvel values a joint of MuJoCo's type `type` has: free
// 7 and 6, ball 4 and 3, slide and hinge 1 and 1; and the type's word.
struct JointSize {
  int nq;
  int nv;
};
[[nodiscard]] JointSize joint_size(int type) noexcept;
[[nodiscard]] const char* joint_type_name(int type) noexcept;

}  // namespace simloop
