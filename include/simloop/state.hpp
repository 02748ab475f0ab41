// A simulation's full state as one flat array of doubles, for saving,
// restoring, copying and starting batches from: everything mj_step reads
// that is not the model, so that set_state(get_state(d)) and stepping gives
// the bits the original would have given. Its layout depends on the MuJoCo
// simloop is built on (state_layout names the parts):
//
// - MuJoCo 3.3 and later (the PyPI build): exactly mj_getState(m, d, state,
//   mjSTATE_INTEGRATION), so mujoco.mj_setState takes it as it is, then,
//   from 3.4, the kinematic trees' sleep counters (d->tree_asleep, ntree
//   values; mj_getState leaves them out, and without them a restore wakes
//   every sleeping body).
// - MuJoCo 2.2 (Debian's) has no mj_getState; the same idea, in order:
//     time (1), qpos (nq), qvel (nv), act (na), qacc_warmstart (nv),
//     ctrl (nu), qfrc_applied (nv), xfrc_applied (6 nbody),
//     mocap_pos (3 nmocap), mocap_quat (4 nmocap), userdata (nuserdata)
//
// The warmstart is part of it because MuJoCo's constraint solver starts from
// it: leave it out and a restored run differs in the last bits.
//
// MuJoCo's own state, a buffer of mj_getState(m, d, s, mjSTATE_INTEGRATION)
// from the same MuJoCo, is taken wherever a state is (set_state, a run's
// initial_state): by its length, mujoco_state_size(m). That is unambiguous by
// construction: simloop's state is MuJoCo's followed by ntree sleep counters,
// so the two lengths differ by ntree, and where ntree is 0 (or on 3.3, which
// has no sleep) the two are the same values in the same order; no other
// signature of mj_getState is longer than mjSTATE_INTEGRATION's. A MuJoCo
// state has every kinematic tree awake. MuJoCo 2.2 has no mj_getState, so
// there only simloop's layout is taken.
#pragma once

#include <mujoco/mujoco.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace simloop {

// The state's parts, in order, with their sizes for `m`: ("time", 1), ("qpos", nq), ...
[[nodiscard]] std::vector<std::pair<std::string, std::size_t>> state_layout(const mjModel* m);

// The number of doubles in a state of `m`.
[[nodiscard]] std::size_t state_size(const mjModel* m) noexcept;

// The number of doubles in MuJoCo's mj_getState(mjSTATE_INTEGRATION) state
// of `m`: simloop's first values; 0 on MuJoCo 2.2 (no mj_getState).
[[nodiscard]] std::size_t mujoco_state_size(const mjModel* m) noexcept;

// Whether set_state takes `size` values for `m`: state_size(m), or
// mujoco_state_size(m) where MuJoCo has mj_getState.
[[nodiscard]] bool takes_state_size(const mjModel* m, std::size_t size) noexcept;

// What takes_state_size takes, in words, for an error: "171 values
// (simloop's state, state_layout) or 170 (MuJoCo's mj_getState(...))".
[[nodiscard]] std::string state_sizes_text(const mjModel* m);

// Copies d's state into state[0 .. state_size(m)).
void get_state(const mjModel* m, const mjData* d, double* state) noexcept;
[[nodiscard]] std::vector<double> get_state(const mjModel* m, const mjData* d);

// Writes state[0 .. state_size(m)) into d, derives what MuJoCo derives from it,
// so that what MuJoCo derives from the state (poses, contacts, sensors) is
// current. The caller checks the size; values are taken as they are (a state
// is data MuJoCo itself produced, or the caller's responsibility). Inside
// MuJoCo's error guard, as forward_keeping_state.
void set_state(const mjModel* m, mjData* d, const double* state);
// The same for `size` values: simloop's state or MuJoCo's (every tree awake).
void set_state(const mjModel* m, mjData* d, const double* state, std::size_t size);
// put_state without deriving anything: `size` values, as set_state's.
void put_state(const mjModel* m, mjData* d, const double* state, std::size_t size) noexcept;

// mj_forward without its side effects on the next step: MuJoCo 2.2's
// mj_forward writes its constraint solution into qacc_warmstart, where the
// next mj_step's solver starts, so a plain mj_forward between two steps
// changes the run's bits; it also normalizes free and ball joints'
// quaternions in qpos in place, which the next mj_step does again (not
// idempotent in the last bit). This puts the whole state back as it was.
// Use it to read derived quantities (poses, sensors, contacts) mid-run, as a
// policy does.
//
// Call it inside MuJoCo's error guard (mujoco_call), as any MuJoCo call.
void forward_keeping_state(const mjModel* m, mjData* d);

}  // namespace simloop
