#include "simloop/model.hpp"

#include <cerrno>
#include <cstddef>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "isolated_load.hpp"
#include "model_detail.hpp"
#include "mujoco_compat.hpp"
#include "mujoco_guard.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"

namespace simloop {
namespace {


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

struct ModelDeleter {
  void operator()(const mjModel* m) const noexcept { mj_deleteModel(const_cast<mjModel*>(m)); }
};

// Finds what the loop needs; throws InvalidArgument naming what is missing.
SceneLayout resolve_layout(const mjModel* m, std::string_view source) {
  const std::string where(source);
  SceneLayout at;
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

// mj_loadXML reads from a file name; text in memory goes through a one-file
// virtual file system (compat::OneFileVfs). A scene from outside is compiled
// in a child process (isolated_load.hpp: a failed compile leaves this one as
// it was; about 6 ms more), here if no child can be made; the chapter's own
// scene, known to compile, here.
mjModel* load_xml(const char* filename, const mjVFS* vfs, std::string_view source, std::vector<std::string>& warnings,
                  bool isolated = true) {
  if (isolated) {
    if (mjModel* m = detail::load_xml_in_child(filename, vfs, source, warnings)) return m;
  }
  return detail::load_xml_here(filename, vfs, source, warnings);
}

}  // namespace

Model Model::adopt(mjModel* raw, std::string_view source, std::vector<std::string> load_warnings) {
  std::shared_ptr<const mjModel> owned(raw, ModelDeleter{});
  SceneLayout layout;
  try {
    layout = resolve_layout(raw, source);
  } catch (const InvalidArgument& e) {
    layout = SceneLayout{};
    layout.missing = e.what();
  }
  Model model(std::move(owned), layout);
  model.load_warnings_ = std::make_shared<const std::vector<std::string>>(std::move(load_warnings));
  return model;
}

const SceneLayout& Model::layout() const {
  if (!layout_.missing.empty()) throw InvalidArgument(layout_.missing);
  return layout_;
}

std::string_view pusher_scene_xml() noexcept { return kPusherSceneXml; }

void detail::check_xml_size(std::size_t size, std::string_view source) {
  if (size == 0) {
    throw InvalidArgument(std::string(source) + ": the XML is empty (0 bytes)");
  }
  if (size > kMaxXmlStringBytes) {
    throw InvalidArgument(std::string(source) + ": the XML is " + std::to_string(size) +
                          " bytes; MuJoCo's in-memory loader takes at most " + std::to_string(kMaxXmlStringBytes) +
                          " (write it to a file and load that)");
  }
}

Model Model::from_xml_string(std::string_view xml, std::string_view source) {
  detail::check_xml_size(xml.size(), source);
  detail::install_mujoco_handlers();
  constexpr const char* kName = "model.xml";
  const detail::compat::OneFileVfs vfs(kName, xml, source, "XML");
  std::vector<std::string> warnings;
  mjModel* raw = load_xml(kName, vfs.get(), source, warnings);
  return adopt(raw, source, std::move(warnings));
}

Model Model::pusher_scene() {
  detail::install_mujoco_handlers(/*plugins=*/false);
  const detail::compat::OneFileVfs vfs("model.xml", kPusherSceneXml, "pusher scene", "XML");
  std::vector<std::string> warnings;
  return adopt(load_xml("model.xml", vfs.get(), "pusher scene", warnings, false), "pusher scene", std::move(warnings));
}

Model Model::from_file(const std::string& path) {
  detail::install_mujoco_handlers();
  // MuJoCo's own message for a missing file is vague; check first.
  std::ifstream probe(path);
  if (!probe) {
    throw IoError(path + ": cannot open (" + std::strerror(errno) + ")");
  }
  std::vector<std::string> warnings;
  mjModel* raw = load_xml(path.c_str(), nullptr, path, warnings);
  return adopt(raw, path, std::move(warnings));
}

Model Model::with_timestep(double timestep) const {
  check_positive_seconds("timestep", timestep);
  mjModel* copy = nullptr;
  const mjModel* src = model_.get();
  try {
    detail::mujoco_call([&] { copy = mj_copyModel(nullptr, src); });
  } catch (const MujocoError& e) {
    throw MujocoError(std::string("copying the model for timestep ") + python_float_repr(timestep) + " s: " + e.what());
  }
  copy->opt.timestep = timestep;
  Model model(std::shared_ptr<const mjModel>(copy, ModelDeleter{}), layout_);
  model.load_warnings_ = load_warnings_;
  return model;
}

Model Model::for_run(double timestep, bool energy) const {
  if (timestep == this->timestep() && energy == computes_energy()) return *this;
  Model copy = with_timestep(timestep);
  mjModel* m = const_cast<mjModel*>(copy.get());  // our fresh copy, not yet shared
  m->opt.enableflags = energy ? (m->opt.enableflags | mjENBL_ENERGY) : (m->opt.enableflags & ~mjENBL_ENERGY);
  return copy;
}

Data::Data(const Model& model) {
  const mjModel* m = model.get();
  mjData* d = nullptr;
  try {
    detail::mujoco_call([&] { d = mj_makeData(m); });
  } catch (const MujocoError& e) {
    throw MujocoError(std::string("making the model's mjData: ") + e.what());
  }
  data_.reset(d);
  std::memcpy(sizes_.data(), &m->nq, sizeof sizes_);
  made_for_ = model.model_;
}

bool Data::fits(const Model& model) const noexcept {
  return std::memcmp(sizes_.data(), &model.get()->nq, sizeof sizes_) == 0;
}

// --- Serialization (pickling): MuJoCo's own binary model format.

std::string Model::to_bytes() const {
  const mjModel* m = model_.get();
  int size = 0;
  detail::mujoco_call([&] { size = detail::compat::as_int(mj_sizeModel(m)); });
  std::string bytes(static_cast<std::size_t>(size), '\0');
  char* buffer = bytes.data();
  try {
    detail::mujoco_call([&] { mj_saveModel(m, nullptr, buffer, size); });
  } catch (const MujocoError& e) {
    throw MujocoError(std::string("saving the model as bytes: ") + e.what());
  }
  return bytes;
}

Model Model::from_bytes(std::string_view bytes, std::string_view source) {
  if (bytes.empty() || bytes.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw InvalidArgument(std::string(source) + ": a saved model must be 1 to 2**31-1 bytes, got " +
                          std::to_string(bytes.size()));
  }
  detail::install_mujoco_handlers();
  constexpr const char* kName = "model.mjb";
  const detail::compat::OneFileVfs vfs(kName, bytes, source, "saved model");
  mjModel* raw = nullptr;
  const mjVFS* files = vfs.get();
  try {
    detail::mujoco_call([&] { raw = mj_loadModel(kName, files); });
  } catch (const MujocoError& e) {
    throw MujocoError(std::string(source) + ": loading the saved model: " + e.what());
  }
  if (raw == nullptr) {
    throw MujocoError(std::string(source) + ": not a model MuJoCo " + detail::compat::version_string() +
                      " saved (mj_loadModel refused it)");
  }
  return adopt(raw, source);
}

Model Model::copy_of(const mjModel* m, std::string_view source) {
  detail::install_mujoco_handlers();
  mjModel* copy = nullptr;
  try {
    detail::mujoco_call([&] { copy = mj_copyModel(nullptr, m); });
  } catch (const MujocoError& e) {
    throw MujocoError(std::string(source) + ": copying the model: " + e.what());
  }
  return adopt(copy, source);
}

std::string Model::name() const {
  // MuJoCo's compiler puts the model's name first in the names buffer.
  const mjModel* m = model_.get();
  return m->nnames > 0 ? std::string(m->names) : std::string();
}

std::string mujoco_version() { return "MuJoCo " + detail::compat::version_string(); }

}  // namespace simloop
