// mjModel and mjData, the chapter's two objects, as owning C++ types.
//
// Model is the compiled world: compiled once, then read-only, and shared by
// any number of Data objects (copies of a Model share one mjModel). Data is
// one simulation's state. Keeping them apart is what lets a batch drive many
// independent datas from one compiled model.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <mujoco/mujoco.h>

namespace simloop {

// The chapter's scene: a floor, a free red box, a blue pusher on a slide
// joint along x driven by one motor. Identical to the chapter's XML except for
// <compiler autolimits="true"/>, without which MuJoCo 2.2 rejects the
// motor's ctrlrange (current MuJoCo defaults to it, so it loads on both).
[[nodiscard]] std::string_view pusher_scene_xml() noexcept;

// Where the chapter's loop finds the things it reads and writes, resolved
// once by name. A scene without them still loads (scenarios run on any
// scene); the chapter's loop then refuses it, saying what is missing.
struct SceneLayout {
  int box_body = -1;       // body named "box"
  int box_qposadr = -1;    // its free joint: qpos[adr..adr+7) = xyz + wxyz quaternion
  int box_dofadr = -1;     // qvel[adr..adr+6) = linear velocity (world) + angular (local)
  int pusher_joint = -1;   // the slide/hinge joint that actuator 0 drives
  int pusher_body = -1;    // the body that joint moves
  int pusher_qposadr = -1;
  int pusher_dofadr = -1;
  std::string missing;     // why the scene lacks the chapter's layout ("" when it has it)
};

class Model {
 public:
  // The embedded chapter scene.
  [[nodiscard]] static Model pusher_scene();
  // Any MJCF text. `source` names it in errors.
  [[nodiscard]] static Model from_xml_string(std::string_view xml,
                                             std::string_view source = "<string>");
  // An MJCF file on disk (includes and meshes resolve relative to it).
  [[nodiscard]] static Model from_file(const std::string& path);

  // A copy with opt.timestep set (the model is frozen while stepping; between
  // runs it is ours to edit, as the chapter says). Throws InvalidArgument
  // unless timestep is finite and positive.
  [[nodiscard]] Model with_timestep(double timestep) const;

  // The model a run steps: this one if it already has `timestep` and
  // MuJoCo's energy computation (mjENBL_ENERGY) set as `energy` says,
  // otherwise a copy that has. Energy is a diagnostic: it changes no physics.
  [[nodiscard]] Model for_run(double timestep, bool energy) const;
  [[nodiscard]] bool computes_energy() const noexcept { return (model_->opt.enableflags & mjENBL_ENERGY) != 0; }

  // The compiled model in MuJoCo's binary format (mj_saveModel): what a
  // pickled Model carries. from_bytes loads it back (mj_loadModel through a
  // one-file virtual file system) as a model that steps bit for bit as this
  // one. Throws MujocoError if MuJoCo refuses the bytes.
  [[nodiscard]] std::string to_bytes() const;
  [[nodiscard]] static Model from_bytes(std::string_view bytes, std::string_view source = "<saved model>");
  // A copy (mj_copyModel) of a model someone else owns, such as the one
  // behind a Python mujoco.MjModel: the caller guarantees `m` points to a
  // valid mjModel of the very libmujoco simloop runs.
  [[nodiscard]] static Model copy_of(const mjModel* m, std::string_view source);
  // <mujoco model="...">'s name ("" if the scene has none).
  [[nodiscard]] std::string name() const;

  [[nodiscard]] const mjModel* get() const noexcept { return model_.get(); }
  [[nodiscard]] double timestep() const noexcept { return model_->opt.timestep; }
  // The chapter's layout: a body "box" on a free joint and an actuator 0
  // that drives a slide or hinge joint. Throws InvalidArgument naming what
  // the scene lacks.
  [[nodiscard]] const SceneLayout& layout() const;
  [[nodiscard]] bool has_chapter_layout() const noexcept { return layout_.missing.empty(); }
  // Why the scene lacks the chapter's layout, naming the model ("" if it has it).
  [[nodiscard]] const std::string& missing_layout() const noexcept { return layout_.missing; }
  // What MuJoCo warned while it parsed and compiled the scene (its parser's
  // "XML contains a 'NaN'", its compiler's test step's warnings), each on
  // one line; the commands report them as they report stepping warnings.
  [[nodiscard]] const std::vector<std::string>& load_warnings() const noexcept {
    static const std::vector<std::string> none;
    return load_warnings_ ? *load_warnings_ : none;
  }

 private:
  // Takes ownership of a freshly loaded model and resolves its layout.
  static Model adopt(mjModel* raw, std::string_view source, std::vector<std::string> load_warnings = {});
  Model(std::shared_ptr<const mjModel> model, SceneLayout layout)
      : model_(std::move(model)), layout_(layout) {}
  std::shared_ptr<const mjModel> model_;
  SceneLayout layout_;
  std::shared_ptr<const std::vector<std::string>> load_warnings_;
  friend class Data;  // which mjModel a Data was made for
};

// One simulation's state, sized for a model. A Data may be reused for any
// Model of the same structure (for example the same scene at another
// timestep): runs reset it first.
class Data {
 public:
  explicit Data(const Model& model);
  [[nodiscard]] mjData* get() noexcept {
    fresh_ = false;  // whoever has the mjData may change it
    return data_.get();
  }
  [[nodiscard]] const mjData* get() const noexcept { return data_.get(); }
  // True if this data was made for a model of the same sizes as `model`
  // (every size field of mjModel, nq through nbuffer, is equal).
  [[nodiscard]] bool fits(const Model& model) const noexcept;
  // True while this data is as mj_makeData left it for `model`'s own mjModel
  // (reset to it) and nobody has had its mjData since: a run need not reset it.
  [[nodiscard]] bool fresh_for(const Model& model) const noexcept {
    return fresh_ && !made_for_.owner_before(model.model_) && !model.model_.owner_before(made_for_);
  }

 private:
  struct Deleter {
    void operator()(mjData* d) const noexcept { mj_deleteData(d); }
  };
  std::unique_ptr<mjData, Deleter> data_;
  // mjModel's leading block of sizes, nq through nbuffer (int in MuJoCo
  // 2.2, mjtSize from 3.5: the type is the model's own).
  using SizeField = decltype(mjModel::nq);
  static constexpr std::size_t kSizeFields =
      (offsetof(mjModel, nbuffer) - offsetof(mjModel, nq)) / sizeof(SizeField) + 1;
  std::array<SizeField, kSizeFields> sizes_{};
  std::weak_ptr<const mjModel> made_for_;
  bool fresh_ = true;
};

// "MuJoCo 2.2.2": the version of the library we are linked against.
[[nodiscard]] std::string mujoco_version();

}  // namespace simloop
