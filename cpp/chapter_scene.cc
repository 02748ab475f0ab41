#include "simloop/chapter_scene.hpp"

#include "mujoco_guard.hpp"
#include "simloop/errors.hpp"

namespace simloop {
namespace {

// bench/bare_chapter.c loads this very text (cmake/SceneXmlHeader.cmake takes
// it from here at build time).
constexpr std::string_view kPusherSceneXml = R"(<mujoco model="pusher_scene">
  <compiler autolimits="true"/>
  <worldbody>
    <light pos="0 0 3" dir="0 0 -1"/>
    <geom name="floor" type="plane" size="2 2 0.1" rgba="0.85 0.85 0.85 1"/>
    <body name="box" pos="0.4 0 0.05">
      <freejoint/>
      <geom name="box_geom" type="box" size="0.05 0.05 0.05" mass="0.5" rgba="0.85 0.3 0.25 1"/>
    </body>
    <body name="pusher" pos="0 0 0.05">
      <joint name="pusher_slide" type="slide" axis="1 0 0" damping="4"/>
      <geom name="pusher_geom" type="box" size="0.04 0.12 0.05" mass="1.0" rgba="0.25 0.45 0.85 1"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="push_motor" joint="pusher_slide" gear="10" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
)";

}  // namespace

ChapterLayout chapter_layout(const Model& model) {
  const mjModel* m = model.get();
  const std::string& where = model.source();
  ChapterLayout at;
  at.box_body = mj_name2id(m, mjOBJ_BODY, "box");
  if (at.box_body < 0) {
    throw InvalidArgument(where + ": the model has no body named \"box\"");
  }
  if (m->body_jntnum[at.box_body] != 1 || m->jnt_type[m->body_jntadr[at.box_body]] != mjJNT_FREE) {
    throw InvalidArgument(where + ": body \"box\" must have exactly one joint, a free joint");
  }
  const int box_joint = m->body_jntadr[at.box_body];
  at.box_qposadr = m->jnt_qposadr[box_joint];
  at.box_dofadr = m->jnt_dofadr[box_joint];

  if (m->nu < 1) {
    throw InvalidArgument(where + ": the model has no actuator (the loop writes ctrl[0])");
  }
  if (m->actuator_trntype[0] != mjTRN_JOINT) {
    throw InvalidArgument(where + ": actuator 0 must drive a joint (the pusher)");
  }
  at.pusher_joint = m->actuator_trnid[0];
  const int type = m->jnt_type[at.pusher_joint];
  if (type != mjJNT_SLIDE && type != mjJNT_HINGE) {
    throw InvalidArgument(where + ": actuator 0 must drive a slide or hinge joint (its position is pusher_x)");
  }
  at.pusher_body = m->jnt_bodyid[at.pusher_joint];
  at.pusher_qposadr = m->jnt_qposadr[at.pusher_joint];
  at.pusher_dofadr = m->jnt_dofadr[at.pusher_joint];
  return at;
}

std::string chapter_layout_missing(const Model& model) {
  try {
    (void)chapter_layout(model);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return {};
}

std::string_view pusher_scene_xml() noexcept { return kPusherSceneXml; }

Model pusher_scene() { return Model::from_own_xml(kPusherSceneXml, "pusher scene"); }

PusherTrack pusher_track(const Model& model) {
  const mjModel* m = model.get();
  const ChapterLayout at = chapter_layout(model);
  Data scratch(model);  // as mj_resetData leaves it: the rest pose
  mjData* d = scratch.get();
  detail::mujoco_call([&] { mj_kinematics(m, d); });
  PusherTrack track;
  for (int i = 0; i < 3; ++i) track.rest_position[i] = d->xpos[3 * at.pusher_body + i];
  if (m->jnt_type[at.pusher_joint] == mjJNT_SLIDE) {
    for (int i = 0; i < 3; ++i) track.axis[i] = d->xaxis[3 * at.pusher_joint + i];
  }
  track.q0 = m->qpos0[at.pusher_qposadr];
  return track;
}

}  // namespace simloop
