// The seam's part for the physics state (simloop/state.hpp): MuJoCo 3.3
// and later's mj_getState(mjSTATE_INTEGRATION) and sleep counters, and
// MuJoCo 2.2's own list of the same parts.
#include <algorithm>
#include <array>
#include <cstring>

#include "mujoco_compat.hpp"

namespace simloop::detail::compat {

#if mjVERSION_HEADER >= 300
namespace {

constexpr int kStateSignature = mjSTATE_INTEGRATION;
constexpr const char* kStateNames[] = {
#include "simloop/mujoco_state_names.inc"
};
static_assert(std::size(kStateNames) == mjNSTATE, "the state names read from the headers are MuJoCo's");

// MuJoCo 3.4 put bodies to sleep: d->tree_asleep counts each kinematic tree
// towards sleep and is not part of mj_getState, so a state without it wakes
// every sleeping tree on restore. It goes after MuJoCo's own state, as doubles.
#if mjVERSION_HEADER >= 340
std::size_t sleep_size(const mjModel* m) noexcept { return count(m->ntree); }
}  // namespace
// Recomputes d's derived sleep arrays (tree_awake, body_awake, ...) from
// tree_asleep. Exported by libmujoco since 3.4 but not declared in its
// headers; without it the next step sees trees asleep by tree_asleep yet
// awake by tree_awake, and wakes them ("perturbation").
extern "C" void mj_updateSleep(const mjModel* m, mjData* d);
namespace {
#else
std::size_t sleep_size(const mjModel*) noexcept { return 0; }
#endif

}  // namespace

std::size_t mujoco_state_size(const mjModel* m) noexcept {
  return static_cast<std::size_t>(mj_stateSize(m, kStateSignature));
}

void get_mujoco_state(const mjModel* m, const mjData* d, double* state) noexcept {
  mj_getState(m, d, state, kStateSignature);
}

std::vector<std::pair<std::string, std::size_t>> state_layout(const mjModel* m) {
  std::vector<std::pair<std::string, std::size_t>> layout;
  for (int i = 0; i < mjNSTATE; ++i) {
    const int element = 1 << i;
    if ((kStateSignature & element) == 0) continue;
    std::string name = kStateNames[i] + std::strlen("mjSTATE_");
    std::transform(name.begin(), name.end(), name.begin(),
                   [](char c) { return c >= 'A' && c <= 'Z' ? char(c + 32) : c; });
    layout.emplace_back(std::move(name), static_cast<std::size_t>(mj_stateSize(m, element)));
  }
  if (sleep_size(m) > 0) layout.emplace_back("tree_asleep", sleep_size(m));
  return layout;
}

std::size_t state_size(const mjModel* m) noexcept { return mujoco_state_size(m) + sleep_size(m); }

void get_state(const mjModel* m, const mjData* d, double* state) noexcept {
  mj_getState(m, d, state, kStateSignature);
#if mjVERSION_HEADER >= 340
  std::copy_n(d->tree_asleep, sleep_size(m), state + mujoco_state_size(m));
#endif
}

void put_state(const mjModel* m, mjData* d, const double* state) noexcept {
  mj_setState(m, d, state, kStateSignature);
#if mjVERSION_HEADER >= 340
  const double* asleep = state + mujoco_state_size(m);
  for (std::size_t i = 0; i < sleep_size(m); ++i) d->tree_asleep[i] = static_cast<int>(asleep[i]);
  mj_updateSleep(m, d);
#endif
}

bool state_all_awake(const mjModel* m, const double* state) noexcept {
  return std::all_of(state + mujoco_state_size(m), state + state_size(m), [](double counter) { return counter < 0; });
}

void put_state_awake(const mjModel* m, mjData* d, const double* state) noexcept {
  mj_setState(m, d, state, kStateSignature);
#if mjVERSION_HEADER >= 340
  std::fill_n(d->tree_asleep, sleep_size(m), -(1 + mjMINAWAKE));  // MuJoCo's "fully awake"
  mj_updateSleep(m, d);
#endif
}

#else
// ---------------------------------------------------------------- MuJoCo 2.2

namespace {

// MuJoCo 2.2 has no mj_getState; this is the same idea as later MuJoCo's
// mjSTATE_INTEGRATION, in this order. These two lists serve get, put and
// the layout, so they cannot disagree.
constexpr std::size_t kParts = 11;
constexpr std::array<const char*, kParts> kNames = {"time",           "qpos",       "qvel",         "act",
                                                    "qacc_warmstart", "ctrl",       "qfrc_applied", "xfrc_applied",
                                                    "mocap_pos",      "mocap_quat", "userdata"};

std::array<std::size_t, kParts> sizes(const mjModel* m) noexcept {
  return {1,
          count(m->nq),
          count(m->nv),
          count(m->na),
          count(m->nv),
          count(m->nu),
          count(m->nv),
          6 * count(m->nbody),
          3 * count(m->nmocap),
          4 * count(m->nmocap),
          count(m->nuserdata)};
}

template <typename D>
auto places(D* d) noexcept {
  return std::array<decltype(&d->time), kParts>{&d->time,          d->qpos,       d->qvel,         d->act,
                                                d->qacc_warmstart, d->ctrl,       d->qfrc_applied, d->xfrc_applied,
                                                d->mocap_pos,      d->mocap_quat, d->userdata};
}

}  // namespace

std::vector<std::pair<std::string, std::size_t>> state_layout(const mjModel* m) {
  const auto size = sizes(m);
  std::vector<std::pair<std::string, std::size_t>> layout;
  for (std::size_t i = 0; i < kParts; ++i) layout.emplace_back(kNames[i], size[i]);
  return layout;
}

std::size_t state_size(const mjModel* m) noexcept {
  std::size_t total = 0;
  for (const std::size_t size : sizes(m)) total += size;
  return total;
}

void get_state(const mjModel* m, const mjData* d, double* state) noexcept {
  const auto size = sizes(m);
  const auto source = places(d);
  for (std::size_t i = 0; i < kParts; ++i) state = std::copy_n(source[i], size[i], state);
}

void put_state(const mjModel* m, mjData* d, const double* state) noexcept {
  const auto size = sizes(m);
  const auto target = places(d);
  for (std::size_t i = 0; i < kParts; ++i) {
    std::copy_n(state, size[i], target[i]);
    state += size[i];
  }
}

bool state_all_awake(const mjModel*, const double*) noexcept { return true; }
void put_state_awake(const mjModel* m, mjData* d, const double* state) noexcept { put_state(m, d, state); }

std::size_t mujoco_state_size(const mjModel*) noexcept { return 0; }
void get_mujoco_state(const mjModel*, const mjData*, double*) noexcept {}

#endif

}  // namespace simloop::detail::compat
