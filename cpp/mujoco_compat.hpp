// The one seam between simloop and the MuJoCo it is built on: Debian 12's
// 2.2.2 (the default) or the PyPI package's 3.3 to 4.x (SIMLOOP_MUJOCO=pypi).
// Everything that differs between them is here; the rest of the library
// calls these and never tests a version itself.
//
//   what               2.2.2                              3.3 .. 4.x
//   version string     mj_version() 222                   mj_version() 330, then 3005000 from 3.5
//   in-memory files    mjVFS of fixed arrays              opaque mjVFS, mj_addBufferVFS (3.2)
//   warnings           8, mjWARN_VGEOMFULL among them     7 from 3.7; names from the headers
//   warning text       mju_warningText's static buffer    thread-local (2.3.1)
//   model sizes        int                                mjtSize, int64 (3.5)
//   state              our own layout (MuJoCo has none)   mj_getState(mjSTATE_INTEGRATION), then
//                                                         the trees' sleep counters (3.4)
//   data's memory      nbuffer + nstack mjtNums           nbuffer + narena bytes
//   plugins            none                               libraries in the package's plugin/ folder
//   arrays             mjxmacro.h: sizes MJMODEL_INTS,     MJMODEL_SIZES; contacts and constraints
//                      contacts and constraints njmax-    in d->arena, nefc/ncon rows (MJ_D)
//                      and nconmax-sized, nefc/ncon used  actuator outputs nout (= nu: actuator rows)
#pragma once

#include <mujoco/mujoco.h>

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "simloop/fields.hpp"

namespace simloop::detail::compat {

// True when built on MuJoCo 3 or later (the PyPI package).
inline constexpr bool kMujoco3 = mjVERSION_HEADER >= 300;

// The running library's version as MuJoCo spells it: "2.2.2", "3.17.0".
[[nodiscard]] std::string version_string();

// A model size (int in 2.2, mjtSize from 3.5) as a count of elements.
template <class Size>
[[nodiscard]] constexpr std::size_t count(Size n) noexcept {
  return static_cast<std::size_t>(n);
}

// A model size as the int that MuJoCo's own functions take and return:
// every size of a model that loaded fits (MuJoCo's arrays are indexed by int).
template <class Size>
[[nodiscard]] constexpr int as_int(Size n) noexcept {
  return static_cast<int>(n);
}

// A virtual file system holding one file, `name`, with `contents`, for
// MuJoCo's loaders to read from memory. Throws MujocoError or Error naming
// `source` and `what` it holds if MuJoCo cannot take it.
class OneFileVfs {
 public:
  OneFileVfs(const char* name, std::string_view contents, std::string_view source, const char* what);
  ~OneFileVfs();
  OneFileVfs(const OneFileVfs&) = delete;
  OneFileVfs& operator=(const OneFileVfs&) = delete;
  [[nodiscard]] const mjVFS* get() const noexcept { return vfs_.get(); }

 private:
  std::unique_ptr<mjVFS> vfs_;
};

// mj_loadXML, with simloop's own bound on what MuJoCo would take hours to
// compile: MuJoCo 3 and later add <size nkey="N"> keyframes one at a time
// (2^31 of them ran for hours where 2.2 ran out of memory at once), so from
// 3.x the XML is parsed first and more than kMaxKeyframes refused, with
// the reason in `error`. Returns nullptr with `error` set on failure; a model
// with `error` holding the compiler's warning, if any. Call it
// inside MuJoCo's error guard.
inline constexpr int kMaxKeyframes = 1000000;
inline constexpr int kMaxUserNumbers = 1000000;  // <size nuserdata>, <size nuser_body> and the like
[[nodiscard]] mjModel* load_xml(const char* filename, const mjVFS* vfs, char* error, int error_size);

// The bytes one mjData holds: its buffer and its stack (2.2's nstack
// mjtNums) or arena (3.x's narena bytes).
[[nodiscard]] std::size_t data_bytes(const mjData* d) noexcept;

// MuJoCo's warnings: how many, each one's name ("mjWARN_BADQACC", from the
// headers) and its message for a given info, as mju_warningText words it.
inline constexpr int kWarningCount = mjNWARNING;
[[nodiscard]] const char* warning_name(int warning) noexcept;
[[nodiscard]] std::string warning_text(int warning, int info);

// The full physics state (see simloop/state.hpp): its parts and sizes, its
// size, and copying it out of and into d (put_state derives nothing).
[[nodiscard]] std::vector<std::pair<std::string, std::size_t>> state_layout(const mjModel* m);
[[nodiscard]] std::size_t state_size(const mjModel* m) noexcept;
void get_state(const mjModel* m, const mjData* d, double* state) noexcept;
void put_state(const mjModel* m, mjData* d, const double* state) noexcept;
// MuJoCo's own state, mj_getState(mjSTATE_INTEGRATION): state_size's first
// mujoco_state_size values (the rest are 3.4's sleep counters). 0 on 2.2,
// which has no mj_getState (get_mujoco_state then writes nothing).
[[nodiscard]] std::size_t mujoco_state_size(const mjModel* m) noexcept;
void get_mujoco_state(const mjModel* m, const mjData* d, double* state) noexcept;
// put_state with every kinematic tree awake (no sleep on 2.2: the same), so
// that an mj_forward after it derives every body's pose, sleeping or not.
void put_state_awake(const mjModel* m, mjData* d, const double* state) noexcept;
// No kinematic tree of `state` is asleep (always, on 2.2): an mj_step from it
// derives every body's pose itself, from stale poses or not.
[[nodiscard]] bool state_all_awake(const mjModel* m, const double* state) noexcept;

// One of mjModel's or mjData's arrays as mjxmacro.h lists it: its rows (in
// use now, for the contacts' and constraints') and the size that counts
// them ("nbody", "nefc").
struct RawArray {
  std::string_view name;
  std::string_view rows_count;
  void* data;
  Element element;
  long long rows;
  long long cols;
};
// Calls visit(array) for each numeric array of m (of d), in MuJoCo's order,
// until visit returns true; true if it did.
bool each_model_array(const mjModel* m, const std::function<bool(const RawArray&)>& visit);
bool each_data_array(const mjModel* m, const mjData* d, const std::function<bool(const RawArray&)>& visit);

// Where MuJoCo's warnings go (mujoco_compat_log.cc): those raised while
// `in_simloop()` (inside one of simloop's calls, or while a load listens) to
// `simloop`; every other exactly where MuJoCo would have sent it without
// simloop (the legacy mju_user_warning, or MuJoCo 4's log handler, that was
// there before, or MuJoCo's default). Installed once per process; later
// calls do nothing.
struct WarningRoute {
  bool (*in_simloop)() noexcept = nullptr;
  void (*simloop)(const char* message) = nullptr;
};
void install_warning_route(WarningRoute route);

// Loads the plugin libraries that ship beside libmujoco (its plugin/
// folder), once per process, so scenes that use MuJoCo's first-party
// plugins (elasticity, sdf, actuator, sensor) load. Nothing on 2.2.
void load_plugins_once();
// Whether the model has plugin instances (their state may change at each
// call of theirs). None on 2.2.
[[nodiscard]] inline bool has_plugins(const mjModel* m) noexcept {
#if mjVERSION_HEADER >= 300
  return m->nplugin > 0;
#else
  (void)m;
  return false;
#endif
}

}  // namespace simloop::detail::compat
