#include "simloop/state.hpp"

#include <algorithm>
#include <array>

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

void forward_keeping_warmstart(const mjModel* m, mjData* d) {
  // mj_forward leaves its solution in qacc_warmstart (MuJoCo 2.2), and the
  // next mj_step starts its solver from there: put the old one back.
  const std::vector<mjtNum> warmstart(d->qacc_warmstart, d->qacc_warmstart + m->nv);
  mj_forward(m, d);
  std::copy(warmstart.begin(), warmstart.end(), d->qacc_warmstart);
}

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

void set_state(const mjModel* m, mjData* d, const double* state) {
  const auto size = sizes(m);
  const auto target = places(d);
  for (std::size_t i = 0; i < kParts; ++i) {
    std::copy_n(state, size[i], target[i]);
    state += size[i];
  }
  forward_keeping_warmstart(m, d);
}

}  // namespace simloop
