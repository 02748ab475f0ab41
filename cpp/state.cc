#include "simloop/state.hpp"

#include <algorithm>
#include <array>
#include <vector>

namespace simloop {
namespace {

// The parts' sizes for m, and where they live in d, in the order state.hpp
// gives. These two lists serve get, set and the layout, so they cannot disagree.
constexpr std::size_t kParts = 11;
constexpr std::array<const char*, kParts> kNames = {
    "time", "qpos", "qvel", "act", "qacc_warmstart", "ctrl", "qfrc_applied", "xfrc_applied",
    "mocap_pos", "mocap_quat", "userdata"};

std::array<std::size_t, kParts> sizes(const mjModel* m) noexcept {
  const auto n = [](int k) { return static_cast<std::size_t>(k); };
  return {1, n(m->nq), n(m->nv), n(m->na), n(m->nv), n(m->nu), n(m->nv), 6 * n(m->nbody),
          3 * n(m->nmocap), 4 * n(m->nmocap), n(m->nuserdata)};
}

template <typename D>
auto places(D* d) noexcept {
  return std::array<decltype(&d->time), kParts>{&d->time, d->qpos, d->qvel, d->act, d->qacc_warmstart,
                                                 d->ctrl, d->qfrc_applied, d->xfrc_applied, d->mocap_pos,
                                                 d->mocap_quat, d->userdata};
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

std::vector<double> get_state(const mjModel* m, const mjData* d) {
  std::vector<double> state(state_size(m));
  get_state(m, d, state.data());
  return state;
}

namespace {
void put_state(const mjModel* m, mjData* d, const double* state) noexcept {
  const auto size = sizes(m);
  const auto target = places(d);
  for (std::size_t i = 0; i < kParts; ++i) {
    std::copy_n(state, size[i], target[i]);
    state += size[i];
  }
}
}  // namespace

void set_state(const mjModel* m, mjData* d, const double* state) {
  put_state(m, d, state);
  forward_keeping_state(m, d);
}

void forward_keeping_state(const mjModel* m, mjData* d) {
  // MuJoCo 2.2's mj_forward leaves its solution in qacc_warmstart, where the
  // next mj_step's solver starts, and normalizes the quaternions of free and
  // ball joints in qpos in place; normalizing is not idempotent in the last
  // bit, and the next mj_step normalizes them again. Either changes the
  // run's bits, so the whole state goes back as it was (the derived
  // quantities are those of the normalized quaternions, as mj_step's own).
  std::vector<double> state(state_size(m));
  get_state(m, d, state.data());
  mj_forward(m, d);
  put_state(m, d, state.data());
}

}  // namespace simloop
