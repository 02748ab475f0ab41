#include "mujoco_compat.hpp"

#include <link.h>
#include <mujoco/mjxmacro.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <system_error>
#include <type_traits>

#include "mujoco_guard.hpp"
#include "simloop/errors.hpp"

namespace simloop::detail::compat {
namespace {

constexpr const char* kWarningNames[] = {
#include "simloop/mujoco_warning_names.inc"
};
static_assert(std::size(kWarningNames) == mjNWARNING, "the warning names read from the headers are MuJoCo's");

}  // namespace

std::string version_string() { return mj_versionString(); }

mjModel* load_xml(const char* filename, const mjVFS* vfs, char* error, int error_size) {
#if mjVERSION_HEADER >= 300
  mjSpec* spec = mj_parseXML(filename, vfs, error, error_size);
  if (spec == nullptr) return nullptr;
  mjModel* m = nullptr;
  // Sizes MuJoCo 3's compiler fills element by element (2^31 user numbers a
  // body allocated for minutes, then crashed): refused before compiling.
  const std::pair<const char*, int> user_sizes[] = {
      {"nuserdata", spec->nuserdata},       {"nuser_body", spec->nuser_body},
      {"nuser_jnt", spec->nuser_jnt},       {"nuser_geom", spec->nuser_geom},
      {"nuser_site", spec->nuser_site},     {"nuser_cam", spec->nuser_cam},
      {"nuser_tendon", spec->nuser_tendon}, {"nuser_actuator", spec->nuser_actuator},
      {"nuser_sensor", spec->nuser_sensor}};
  const auto too_big = std::find_if(std::begin(user_sizes), std::end(user_sizes),
                                    [](const auto& size) { return size.second > kMaxUserNumbers; });
  if (spec->nkey > kMaxKeyframes) {
    std::snprintf(error, static_cast<std::size_t>(error_size),
                  "<size nkey=\"%d\"> asks for %d keyframes; simloop loads at most %d", spec->nkey, spec->nkey,
                  kMaxKeyframes);
  } else if (too_big != std::end(user_sizes)) {
    std::snprintf(error, static_cast<std::size_t>(error_size), "<size %s=\"%d\"> is more than simloop loads (%d)",
                  too_big->first, too_big->second, kMaxUserNumbers);
  } else {
    m = mj_compile(spec, vfs);
    // A failed compile's error, or a compiled model's warning (as mj_loadXML).
    if (m == nullptr || mjs_isWarning(spec)) {
      std::snprintf(error, static_cast<std::size_t>(error_size), "%s", mjs_getError(spec));
    }
  }
  mj_deleteSpec(spec);
  return m;
#else
  mjModel* m = mj_loadXML(filename, vfs, error, error_size);
  // Today's scenes use words 2.2 does not know (implicitfast, <size memory>,
  // actuatorfrcrange, ...): say which MuJoCo this is and how to get the other.
  if (m == nullptr &&
      (std::strstr(error, "Schema violation") != nullptr || std::strstr(error, "invalid keyword") != nullptr)) {
    const std::size_t used = std::strlen(error);
    std::snprintf(error + used, static_cast<std::size_t>(error_size) - used,
                  " (this simloop runs MuJoCo %s; for a scene written for newer MuJoCo, build it on the mujoco "
                  "package: SIMLOOP_MUJOCO=pypi scripts/run.sh)",
                  mj_versionString());
  }
  // A range without its limited flag (the chapter's own SCENE_XML: ctrlrange
  // without ctrllimited), which current MuJoCo accepts: say the one line
  // that makes 2.2 take it.
  if (m == nullptr && std::strstr(error, "autolimits") != nullptr) {
    const std::size_t used = std::strlen(error);
    std::snprintf(error + used, static_cast<std::size_t>(error_size) - used,
                  " (to fix it, put <compiler autolimits=\"true\"/> inside <mujoco>, before <worldbody>: current "
                  "MuJoCo does this by default, MuJoCo %s does not)",
                  mj_versionString());
  }
  return m;
#endif
}

const char* warning_name(int warning) noexcept {
  return warning >= 0 && warning < mjNWARNING ? kWarningNames[warning] : "mjWARN_UNKNOWN";
}

#if mjVERSION_HEADER >= 300
// ---------------------------------------------------------------- MuJoCo 3.3 .. 4.x

namespace {
// Adds `contents` to vfs as the file `name`; MuJoCo's status, 0 when done.
int add_file(mjVFS* vfs, const char* name, std::string_view contents) {
  return mj_addBufferVFS(vfs, name, contents.data(), static_cast<int>(contents.size()));
}
}  // namespace

std::string warning_text(int warning, int info) {
  // Thread-local in MuJoCo since 2.3.1: safe while batches step in threads.
  return mju_warningText(warning, static_cast<std::size_t>(std::max(info, 0)));
}

namespace {
// The folder of the libmujoco this process runs: the one whose file name
// starts with libmujoco.so among the loaded objects.
int find_libmujoco(dl_phdr_info* info, std::size_t, void* out) {
  const char* path = info->dlpi_name;
  if (path == nullptr || *path == '\0') return 0;
  const std::filesystem::path file(path);
  if (file.filename().string().rfind("libmujoco.so", 0) != 0) return 0;
  *static_cast<std::filesystem::path*>(out) = file.parent_path();
  return 1;
}
}  // namespace

void load_plugins_once() {
  static std::once_flag once;
  std::call_once(once, [] {
    std::filesystem::path folder;
    dl_iterate_phdr(find_libmujoco, &folder);
    if (folder.empty()) return;
    const std::string plugins = (folder / "plugin").string();
    std::error_code error;
    if (!std::filesystem::is_directory(plugins, error)) return;
    // A plugin library that fails to load leaves its plugins unknown; the
    // scene that names one then fails to load with MuJoCo's own message.
    const char* dir = plugins.c_str();
    (void)call_catching_mujoco_error([](void* p) { mj_loadAllPluginLibraries(static_cast<const char*>(p), nullptr); },
                                     const_cast<char*>(dir));
  });
}

#else
// ---------------------------------------------------------------- MuJoCo 2.2

namespace {
// 2.2's mjVFS is fixed arrays (2 MB): a file is made empty, then filled in place.
int add_file(mjVFS* vfs, const char* name, std::string_view contents) {
  const int status = mj_makeEmptyFileVFS(vfs, name, static_cast<int>(contents.size()));
  if (status == 0) std::memcpy(vfs->filedata[vfs->nfile - 1], contents.data(), contents.size());
  return status;
}
}  // namespace

// 2.2's texts (mju_warningText), rebuilt because that function writes one
// shared static buffer and batches step in threads.
std::string warning_text(int warning, int info) {
  static constexpr const char* kFormats[mjNWARNING] = {
      "Inertia matrix is too close to singular at DOF %d. Check model.",
      "Pre-allocated contact buffer is full. Increase nconmax above %d.",
      "Pre-allocated constraint buffer is full. Increase njmax above %d.",
      "Pre-allocated visual geom buffer is full. Increase maxgeom above %d.",
      "Nan, Inf or huge value in QPOS at DOF %d. The simulation is unstable.",
      "Nan, Inf or huge value in QVEL at DOF %d. The simulation is unstable.",
      "Nan, Inf or huge value in QACC at DOF %d. The simulation is unstable.",
      "Nan, Inf or huge value in CTRL at ACTUATOR %d. The simulation is unstable."};
  if (warning < 0 || warning >= mjNWARNING) return "Unknown warning type " + std::to_string(warning) + ".";
  char text[160];
  std::snprintf(text, sizeof text, kFormats[warning], info);
  return text;
}

void load_plugins_once() {}

#endif

// ---------------------------------------------------------------- both

OneFileVfs::OneFileVfs(const char* name, std::string_view contents, std::string_view source, const char* what)
    : vfs_(new mjVFS) {
  mj_defaultVFS(vfs_.get());
  int status = 0;
  mjVFS* vfs = vfs_.get();
  try {
    // The caller checked that contents' size fits MuJoCo's int.
    mujoco_call([&] { status = add_file(vfs, name, contents); });
  } catch (const MujocoError& e) {
    throw MujocoError(std::string(source) + ": holding the " + what + " in memory: " + e.what());
  }
  if (status != 0) {
    throw Error(std::string(source) + ": could not hold the " + what + " in MuJoCo's virtual file system");
  }
}

OneFileVfs::~OneFileVfs() { mj_deleteVFS(vfs_.get()); }

namespace {

template <class T>
constexpr bool kNumeric = std::is_arithmetic_v<T>;

template <class T>
constexpr Element element_of() {
  if constexpr (std::is_same_v<T, double>) return Element::kFloat64;
  if constexpr (std::is_same_v<T, float>) return Element::kFloat32;
  if constexpr (std::is_same_v<T, char>) return Element::kInt8;
  if constexpr (std::is_same_v<T, unsigned char>) return Element::kUInt8;
  if constexpr (std::is_integral_v<T> && sizeof(T) == 4) return Element::kInt32;
  if constexpr (std::is_integral_v<T> && std::is_signed_v<T> && sizeof(T) == 8) return Element::kInt64;
  return Element::kUInt64;  // uintptr_t, size_t
}

// "MJ_D(nefc)" and "MJ_M(ntendon)" as the size's own name.
std::string_view size_name(std::string_view written) {
  if (written.size() > 6 && (written.substr(0, 5) == "MJ_D(" || written.substr(0, 5) == "MJ_M(")) {
    return written.substr(5, written.size() - 6);
  }
  return written;
}

// Newer MuJoCos size the actuators' outputs by nout (actuator_gear, ...):
// the actuators themselves when each has one output, as every 2.2 actuator does.
template <class M>
auto outputs_are_actuators(const M* m, int) -> decltype(m->nout, bool()) {
  return m->nout == m->nu;
}
template <class M>
bool outputs_are_actuators(const M*, long) {
  return false;
}

template <class T>
bool visit_array(const std::function<bool(const RawArray&)>& visit, const mjModel* m, const char* name,
                 const char* rows_count, T* data, long long rows, long long cols) {
  if constexpr (kNumeric<T>) {
    std::string_view count = size_name(rows_count);
    if (count == "nout" && outputs_are_actuators(m, 0)) count = "nu";
    return visit(RawArray{name, count, const_cast<std::remove_const_t<T>*>(data), element_of<std::remove_const_t<T>>(),
                          rows, cols});
  } else {
    return false;  // the contact structs, the solver's statistics
  }
}

}  // namespace

// The sizes the X macros name (nbody, nuser_body, ...) as locals, then one
// visit per array.
#if mjVERSION_HEADER >= 300
#define SIMLOOP_MODEL_SIZES MJMODEL_SIZES
#else
#define SIMLOOP_MODEL_SIZES MJMODEL_INTS
#endif
#define SIMLOOP_SIZE_LOCAL(n) [[maybe_unused]] const long long n = static_cast<long long>(m->n);

bool each_model_array(const mjModel* m, const std::function<bool(const RawArray&)>& visit) {
#define X SIMLOOP_SIZE_LOCAL
  SIMLOOP_MODEL_SIZES
#undef X
#define X(type, name, rows, cols)                                                                               \
  if (visit_array(visit, m, #name, #rows, m->name, static_cast<long long>(rows), static_cast<long long>(cols))) \
    return true;
#define XNV X
  MJMODEL_POINTERS
#undef XNV
#undef X
  return false;
}

bool each_data_array(const mjModel* m, const mjData* d, const std::function<bool(const RawArray&)>& visit) {
#define X SIMLOOP_SIZE_LOCAL
  SIMLOOP_MODEL_SIZES
#undef X
#if mjVERSION_HEADER >= 300
#undef MJ_D
#define MJ_D(n) d->n
#define X(type, name, rows, cols)                                                                               \
  if (visit_array(visit, m, #name, #rows, d->name, static_cast<long long>(rows), static_cast<long long>(cols))) \
    return true;
#define XNV X
  MJDATA_POINTERS
  MJDATA_ARENA_POINTERS
#undef XNV
#undef X
#undef MJ_D
#define MJ_D(n) n
#else
  // 2.2 sizes the constraints' arrays njmax and the contacts' nconmax; the
  // rows in use are nefc and ncon.
  const auto in_use = [&](std::string_view count, long long rows) -> long long {
    if (count == "njmax") return d->nefc;
    if (count == "nconmax") return d->ncon;
    return rows;
  };
  const auto counted_by = [](std::string_view count) -> const char* {
    return count == "njmax" ? "nefc" : count == "nconmax" ? "ncon" : nullptr;
  };
#define X(type, name, rows, cols)                                                             \
  if (visit_array(visit, m, #name, counted_by(#rows) ? counted_by(#rows) : #rows, d->name,    \
                  in_use(#rows, static_cast<long long>(rows)), static_cast<long long>(cols))) \
    return true;
  MJDATA_POINTERS
#undef X
#endif
  return false;
}

#undef SIMLOOP_SIZE_LOCAL
#undef SIMLOOP_MODEL_SIZES

std::size_t data_bytes(const mjData* d) noexcept {
#if mjVERSION_HEADER >= 300
  return count(d->nbuffer) + count(d->narena);
#else
  return count(d->nbuffer) + count(d->nstack) * sizeof(mjtNum);
#endif
}

}  // namespace simloop::detail::compat
