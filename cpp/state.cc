#include "simloop/state.hpp"

#include <string>
#include <vector>

#include "mujoco_compat.hpp"

namespace simloop {

std::vector<std::pair<std::string, std::size_t>> state_layout(const mjModel* m) {
  return detail::compat::state_layout(m);
}

std::size_t state_size(const mjModel* m) noexcept { return detail::compat::state_size(m); }

std::size_t mujoco_state_size(const mjModel* m) noexcept { return detail::compat::mujoco_state_size(m); }

namespace {
// `size` values are MuJoCo's state, not simloop's (which they equal when the
// two sizes are the same).
bool is_mujocos(const mjModel* m, std::size_t size) noexcept {
  return size != state_size(m) && size == mujoco_state_size(m) && size > 0;
}
}  // namespace

bool takes_state_size(const mjModel* m, std::size_t size) noexcept {
  return size == state_size(m) || is_mujocos(m, size);
}

std::string state_sizes_text(const mjModel* m) {
  std::string text = std::to_string(state_size(m)) + " values (simloop's state, state_layout)";
  if (is_mujocos(m, mujoco_state_size(m))) {
    text += " or " + std::to_string(mujoco_state_size(m)) + " (MuJoCo's mj_getState(mjSTATE_INTEGRATION))";
  }
  return text;
}

void get_state(const mjModel* m, const mjData* d, double* state) noexcept { detail::compat::get_state(m, d, state); }

std::vector<double> get_state(const mjModel* m, const mjData* d) {
  std::vector<double> state(state_size(m));
  get_state(m, d, state.data());
  return state;
}

void set_state(const mjModel* m, mjData* d, const double* state) {
  // MuJoCo skips sleeping bodies when it derives poses, so derive them all
  // with every tree awake, then put the state back exactly, sleep and all
  // (mj_forward also moves the warmstart and renormalizes quaternions: see
  // forward_keeping_state).
  detail::compat::put_state_awake(m, d, state);
  mj_forward(m, d);
  detail::compat::put_state(m, d, state);
}

void put_state(const mjModel* m, mjData* d, const double* state, std::size_t size) noexcept {
  if (is_mujocos(m, size)) {
    detail::compat::put_state_awake(m, d, state);
  } else {
    detail::compat::put_state(m, d, state);
  }
}

void set_state(const mjModel* m, mjData* d, const double* state, std::size_t size) {
  if (!is_mujocos(m, size)) return set_state(m, d, state);
  detail::compat::put_state_awake(m, d, state);
  mj_forward(m, d);
  detail::compat::put_state_awake(m, d, state);
}

void forward_keeping_state(const mjModel* m, mjData* d) {
  // mj_forward leaves its solution in qacc_warmstart, where the next
  // mj_step's solver starts, and normalizes the quaternions of free and
  // ball joints in qpos in place; normalizing is not idempotent in the last
  // bit, and the next mj_step normalizes them again. Either changes the
  // run's bits, so the whole state goes back as it was (the derived
  // quantities are those of the normalized quaternions, as mj_step's own).
  std::vector<double> state(state_size(m));
  get_state(m, d, state.data());
  mj_forward(m, d);
  detail::compat::put_state(m, d, state.data());
}

}  // namespace simloop
