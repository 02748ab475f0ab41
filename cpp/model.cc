#include "simloop/model.hpp"

#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include "isolated_load.hpp"
#include "model_detail.hpp"
#include "mujoco_compat.hpp"
#include "mujoco_guard.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "text_input.hpp"

namespace simloop {
namespace {

struct ModelDeleter {
  void operator()(const mjModel* m) const noexcept { mj_deleteModel(const_cast<mjModel*>(m)); }
};

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
  Model model(std::shared_ptr<const mjModel>(raw, ModelDeleter{}), std::make_shared<const std::string>(source));
  model.load_warnings_ = std::make_shared<const std::vector<std::string>>(std::move(load_warnings));
  return model;
}

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

Model Model::from_own_xml(std::string_view xml, std::string_view source) {
  detail::install_mujoco_handlers(/*plugins=*/false);
  const detail::compat::OneFileVfs vfs("model.xml", xml, source, "XML");
  std::vector<std::string> warnings;
  return adopt(load_xml("model.xml", vfs.get(), source, warnings, false), source, std::move(warnings));
}

Model Model::from_file(const std::string& path) {
  // MuJoCo's own message for a missing file, or a directory, is vague; check first.
  detail::check_regular_file(path, "an MJCF file");
  detail::install_mujoco_handlers();
  std::ifstream probe(path);
  if (!probe) {
    throw IoError(path + ": cannot open (" + std::strerror(errno) + ")");
  }
  std::vector<std::string> warnings;
  try {
    mjModel* raw = load_xml(path.c_str(), nullptr, path, warnings);
    return adopt(raw, path, std::move(warnings));
  } catch (const MujocoError&) {
    // Text that is not XML at all (a scenario's TOML, a CSV): say so, not
    // what MuJoCo's XML parser made of its first line.
    std::string start(64, '\0');
    probe.read(start.data(), static_cast<std::streamsize>(start.size()));
    start.resize(static_cast<std::size_t>(probe.gcount()));
    const std::optional<char> first = detail::first_visible(start);
    if (!first || *first == '<') throw;
    const char c = *first;
    const std::string begins = c >= 0x20 && c < 0x7f ? std::string("begins with '") + c + "', not '<'"
                                                     : std::string("does not begin with '<'");
    throw MujocoError(path + ": not an MJCF scene (its text " + begins +
                      "); a scenario file (TOML) runs as a scenario (--scenario, simloop.Scenario.from_file)");
  }
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
  Model model(std::shared_ptr<const mjModel>(copy, ModelDeleter{}), source_);
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

// --- Serialization (pickling): MuJoCo's own binary model format, then a
// trailer of ours: kSavedModelMagic and the FNV-1a hash of MuJoCo's bytes.
// mj_loadModel checks the format's sizes but not its contents: a damaged
// index would reach mj_makeData and crash it, so damage is caught here first.

namespace {

constexpr std::string_view kSavedModelMagic("simloop\x01", 8);
constexpr std::size_t kTrailerBytes = kSavedModelMagic.size() + sizeof(std::uint64_t);

std::uint64_t fnv1a(std::string_view bytes) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

}  // namespace

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
  const std::uint64_t hash = fnv1a(bytes);
  bytes += kSavedModelMagic;
  bytes.append(reinterpret_cast<const char*>(&hash), sizeof hash);
  return bytes;
}

Model Model::from_bytes(std::string_view saved, std::string_view source) {
  if (saved.size() <= kTrailerBytes ||
      saved.size() - kTrailerBytes > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw InvalidArgument(std::string(source) + ": a saved model must be " + std::to_string(kTrailerBytes + 1) +
                          " to 2**31-1 bytes, got " + std::to_string(saved.size()));
  }
  const std::string_view bytes = saved.substr(0, saved.size() - kTrailerBytes);
  std::uint64_t hash = 0;
  std::memcpy(&hash, saved.data() + bytes.size() + kSavedModelMagic.size(), sizeof hash);
  if (saved.substr(bytes.size(), kSavedModelMagic.size()) != kSavedModelMagic) {
    throw InvalidArgument(std::string(source) + ": not a model simloop saved (Model.to_bytes or a pickle)");
  }
  if (hash != fnv1a(bytes)) {
    throw InvalidArgument(std::string(source) + ": the saved model is damaged (its checksum does not match)");
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
