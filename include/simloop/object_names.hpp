// A scene's objects by name or index, with errors that say what the scene
// has: the one lookup Sim, the renderer's cameras and bodies share.
#pragma once

#include <string>

#include <mujoco/mujoco.h>

namespace simloop {

// The id of the model's object of `type` named `name`. Throws
// InvalidArgument naming what the scene has, with a likely typo's fix:
// "no body named 'torsoo' (did you mean 'torso'?); the scene's bodies: ...".
// Types looked up: bodies, joints, actuators, sensors, keyframes, geoms,
// sites and cameras (InvalidArgument for others).
[[nodiscard]] int object_id(const mjModel* m, mjtObj type, const std::string& name);

// The same for an index: throws InvalidArgument unless 0 <= index < count.
[[nodiscard]] int checked_object_index(const mjModel* m, mjtObj type, long long index);

}  // namespace simloop
