// mjModel and mjData, the chapter's two objects, as owning C++ types.
//
// Model is the compiled world: compiled once, then read-only, and shared by
// any number of Data objects (copies of a Model share one mjModel). Data is
// one simulation's state. Keeping them apart is what lets a batch drive many
// independent datas from one compiled model.
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace simloop {

class Model {
 public:
  // Any MJCF text. `source` names it in errors.
  [[nodiscard]] static Model from_xml_string(std::string_view xml, std::string_view source = "<string>");
  // An MJCF file on disk (includes and meshes resolve relative to it).
  [[nodiscard]] static Model from_file(const std::string& path);
  // The library's own MJCF text (the chapter's scene), known to compile:
  // compiled here, not in a child process as a scene from outside is.
  [[nodiscard]] static Model from_own_xml(std::string_view xml, std::string_view source);

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
  // one. The bytes end in a checksum: InvalidArgument if they are damaged or
  // not simloop's, MujocoError if MuJoCo refuses them.
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
  // Where the model came from, as errors name it: its path, or the
  // `source` it was loaded with.
  [[nodiscard]] const std::string& source() const noexcept { return *source_; }
  // What MuJoCo warned while it parsed and compiled the scene (its parser's
  // "XML contains a 'NaN'", its compiler's test step's warnings), each on
  // one line; the commands report them as they report stepping warnings.
  [[nodiscard]] const std::vector<std::string>& load_warnings() const noexcept {
    static const std::vector<std::string> none;
    return load_warnings_ ? *load_warnings_ : none;
  }

 private:
  // Takes ownership of a freshly loaded model.
  static Model adopt(mjModel* raw, std::string_view source, std::vector<std::string> load_warnings = {});
  Model(std::shared_ptr<const mjModel> model, std::shared_ptr<const std::string> source)
      : model_(std::move(model)), source_(std::move(source)) {}
  std::shared_ptr<const mjModel> model_;
  std::shared_ptr<const std::string> source_;
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
