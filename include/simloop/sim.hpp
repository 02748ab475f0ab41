// The loop's rhythm, one call at a time, for people who write their own loop:
// write intent (ctrl), write interference (a force on a body), step, look.
// Any scene, and nothing of the chapter's own: its parts are found through
// chapter_layout() (chapter_scene.hpp) and read through array(), read() or data().
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "simloop/control.hpp"
#include "simloop/fields.hpp"
#include "simloop/model.hpp"
#include "simloop/rows.hpp"

namespace simloop {

struct Contact {
  // The geoms' names, an unnamed one by kind and index ("geom12", as
  // object_name names it); "" for a side that is no geom (a flex's).
  std::string geom1;
  std::string geom2;
  double dist = 0.0;            // signed distance; negative is penetration, m
  std::array<double, 3> pos{};  // contact point, world frame, m
  // The contact's frame (rows: the normal, from geom1 to geom2, then two
  // tangents; world) and the force and torque geom2 feels in it
  // (mj_contactForce: normal, two frictional, then torsional and rolling
  // torques; N and N m; zero for what the contact's condim does not model).
  std::array<double, 9> frame{};
  std::array<double, 6> force{};
  // The geoms' ids and their bodies' ids and names (-1 and "" for no geom).
  int geom1_id = -1;
  int geom2_id = -1;
  int body1_id = -1;
  int body2_id = -1;
  std::string body1;
  std::string body2;
};

// One of mjData's arrays, as Sim::array names it: `rows` values, or rows x
// `width` when width > 0 (a row a body). writable: an input or the state,
// which a caller may write; otherwise something MuJoCo derives.
struct ArrayView {
  double* data = nullptr;
  int rows = 0;
  int width = 0;
  bool writable = false;
};

class Sim {
 public:
  // A fresh state for `model` (any scene) at t = 0, with mj_forward run so
  // every read is the true rest pose before the first step.
  explicit Sim(const Model& model);

  // An independent copy: its own mjData holding the same state (mj_copyData),
  // the same steps taken and warnings; the compiled model is shared
  // read-only. Stepping one never moves the other.
  Sim(const Sim& other);
  // Not assignable: the mjData a Sim steps is the same one for its whole
  // life, so views into it (the Python bindings' arrays) never dangle.
  Sim& operator=(const Sim&) = delete;

  // Back to t = 0: state, ctrl, applied forces, steps and warnings all cleared.
  void reset();
  // Back to keyframe `key` (0 .. nkey-1) of the model (mj_resetDataKeyframe),
  // steps and warnings cleared. Throws InvalidArgument naming the range.
  void reset_to_keyframe(int key);

  // Sim seconds per step. Changes this Sim's own copy of the model.
  void set_timestep(double timestep);
  [[nodiscard]] double timestep() const noexcept { return model_.timestep(); }

  // The model's object of `type` named `name`: its id. Throws
  // InvalidArgument naming what the scene has, with a likely typo's fix:
  // "no body named 'torsoo' (did you mean 'torso'?); the scene's bodies: ...".
  [[nodiscard]] int id(mjtObj type, const std::string& name) const;
  // The same for an index: throws InvalidArgument unless 0 <= index < count.
  [[nodiscard]] int checked_index(mjtObj type, long long index) const;

  // ctrl[0], the motor's command (the chapter's). Like everything written
  // into mjData it stays until overwritten. Throws InvalidArgument unless
  // finite, or if the model has no actuator.
  void set_ctrl(double value);
  [[nodiscard]] double ctrl() const;
  // The whole ctrl vector: `count` must be nu and every value finite
  // (InvalidArgument naming the sizes or the index).
  void set_ctrl(const double* values, std::size_t count);

  // A force (N) and/or torque (N m) on any body, world frame, at the body's
  // origin, written into its xfrc_applied; a part not given (null) is left
  // as it was. IT PERSISTS: MuJoCo never clears it, so it acts on every
  // following step until cleared (forgetting that is the chapter's classic
  // bug). Throws InvalidArgument for a bad body or a non-finite value,
  // writing nothing.
  void apply_wrench(int body, const std::array<double, 3>* force, const std::array<double, 3>* torque);
  // Zeros every body's xfrc_applied.
  void clear_forces() noexcept;

  // Advances n steps (check_steps) with the current ctrl and forces. With a
  // `control`, a long step can be stopped between chunks (Interrupted; the
  // steps already taken stay taken).
  void step(std::int64_t n = 1, RunControl* control = nullptr);
  // Throws InvalidArgument unless n is from 1 to kMaxSteps: what step()
  // takes, checkable before a caller changes anything else (a ctrl to write).
  static void check_steps(std::int64_t n);

  // Brings what MuJoCo derives from the state (xpos, xquat, cvel, sensors,
  // contacts) up to the current qpos/qvel without changing the next step's
  // bits (forward_keeping_state). After mj_step they describe the state
  // at the start of the step just taken, as in MuJoCo.
  void forward();

  // The full physics state (state.hpp's layout) and back. set_state takes
  // it or MuJoCo's own (mj_getState(mjSTATE_INTEGRATION)), and throws
  // InvalidArgument for any other size; it leaves steps_taken.
  // mujoco_state() is MuJoCo's own state (InvalidArgument on MuJoCo 2.2).
  [[nodiscard]] std::vector<double> state() const;
  [[nodiscard]] std::vector<double> mujoco_state() const;
  void set_state(const double* state, std::size_t size);
  [[nodiscard]] std::size_t state_size() const noexcept;
  [[nodiscard]] std::vector<std::pair<std::string, std::size_t>> state_layout() const;
  // For restoring a saved Sim (pickle): the count steps_taken() reports.
  void set_steps_taken(std::int64_t steps) noexcept { steps_ = steps; }

  // A body's velocity, world frame, at its origin: (wx, wy, wz, vx, vy, vz),
  // from cvel (mj_objectVelocity), as of the last step or forward().
  [[nodiscard]] std::array<double, 6> body_velocity(int body) const;

  [[nodiscard]] double time() const noexcept { return data_.get()->time; }
  [[nodiscard]] std::int64_t steps_taken() const noexcept { return steps_; }
  // The contacts MuJoCo found in its last collision pass.
  [[nodiscard]] std::vector<Contact> contacts() const;
  // Warnings MuJoCo raised since construction or reset.
  [[nodiscard]] std::vector<Warning> warnings() const;

  [[nodiscard]] const Model& model() const noexcept { return model_; }
  // The mjData this Sim steps: the same object for the Sim's whole life.
  // Writes through it take effect at the next step.
  [[nodiscard]] mjData* data() noexcept { return data_.get(); }
  [[nodiscard]] const mjData* data() const noexcept { return data_.get(); }
  // mjData's array `name`: qpos, qvel, ctrl, act, qfrc_applied, xfrc_applied
  // (nbody x 6), mocap_pos (nmocap x 3), mocap_quat (nmocap x 4) writable; sensordata, actuator_force, xpos (nbody x
  // 3), xquat (nbody x 4) not. Throws InvalidArgument for another name.
  [[nodiscard]] ArrayView array(std::string_view name);
  // Any of mjData's arrays (fields.hpp's data_field), read-only: valid
  // until the next step for the contacts' and constraints' (their rows
  // change), for as long as the Sim lives for the others. cacc, cfrc_int,
  // cfrc_ext, subtree_linvel and subtree_angmom are filled for this read
  // (fill_derived): take them again after stepping.
  [[nodiscard]] FieldView data_field(std::string_view name);
  // Any of mjModel's arrays, read-only; writable() for those a trainer
  // randomises (model_field_writable): the first such call gives this Sim a
  // model of its own (a copy; other Sims and runs keep the one they share),
  // which the Sim keeps from then on, so views of it stay valid.
  [[nodiscard]] FieldView model_field(std::string_view name) const;
  [[nodiscard]] FieldView writable_model_field(std::string_view name);
  // A copy of values start .. start+count-1 of array(name), row after row
  // (a joint's slice of qpos, say). Throws InvalidArgument unless they lie
  // inside it.
  [[nodiscard]] std::vector<double> read(std::string_view name, long long start, long long count) const;

 private:
  // The first write to the model (a parameter, the timestep) copies it;
  // after that this Sim writes its own in place.
  mjModel* own_model();

  Model model_;
  bool owns_model_ = false;
  Data data_;
  std::int64_t steps_ = 0;
  struct Stepping;  // the library's stepping core: its warnings, its divergence check
  std::shared_ptr<Stepping> stepping_;
};

}  // namespace simloop
