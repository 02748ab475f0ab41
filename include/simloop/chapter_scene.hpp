// The chapter's scene, and where the chapter's loop finds its box and its
// pusher in any scene that has them. The rest of the library knows no box
// and no pusher: this and the chapter's run (run.hpp) are where they live.
#pragma once

#include <array>
#include <string>
#include <string_view>

#include "simloop/model.hpp"

namespace simloop {

// The chapter's scene: a floor, a free red box, a blue pusher on a slide
// joint along x driven by one motor. Identical to the chapter's XML except for
// <compiler autolimits="true"/>, without which MuJoCo 2.2 rejects the
// motor's ctrlrange (current MuJoCo defaults to it, so it loads on both).
[[nodiscard]] std::string_view pusher_scene_xml() noexcept;
[[nodiscard]] Model pusher_scene();

// Where the chapter's loop finds the things it reads and writes, by name: a
// body "box" on a free joint, and the slide or hinge joint actuator 0 drives
// (the pusher). A scene without them still loads (scenarios run on any
// scene); the chapter's loop then refuses it, saying what is missing.
struct ChapterLayout {
  int box_body = -1;      // body named "box"
  int box_qposadr = -1;   // its free joint: qpos[adr..adr+7) = xyz + wxyz quaternion
  int box_dofadr = -1;    // qvel[adr..adr+6) = linear velocity (world) + angular (local)
  int pusher_joint = -1;  // the slide/hinge joint that actuator 0 drives
  int pusher_body = -1;   // the body that joint moves
  int pusher_qposadr = -1;
  int pusher_dofadr = -1;
};

// Throws InvalidArgument naming the model's source and what the scene lacks.
[[nodiscard]] ChapterLayout chapter_layout(const Model& model);
// That message, or "" if the scene has the chapter's layout.
[[nodiscard]] std::string chapter_layout_missing(const Model& model);

// Where the pusher body is for a given joint position: for a slide joint,
// rest_position + axis * (q - q0); for a hinge, rest_position. Used to draw
// the pusher from the trajectory's pusher_x (exact when the joint's parent
// does not move, as in the chapter's scene).
struct PusherTrack {
  std::array<double, 3> rest_position{};  // body position at qpos0, world
  std::array<double, 3> axis{};           // slide axis, world; zero for a hinge
  double q0 = 0.0;                        // the joint's qpos0
};
[[nodiscard]] PusherTrack pusher_track(const Model& model);

}  // namespace simloop
