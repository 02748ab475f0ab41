#include "simloop/state.hpp"

#include <vector>

#include "mujoco_compat.hpp"

namespace simloop {

std::vector<std::pair<std::string, std::size_t>> state_layout(const mjModel* m) {
  return detail::compat::state_layout(m);
}

std::size_t state_size(const mjModel* m) noexcept { return detail::compat::state_size(m); }

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
