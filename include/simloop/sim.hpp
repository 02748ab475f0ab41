// The loop's rhythm, one call at a time, for people who write their own loop:
// write intent (ctrl), write interference (a force on the box), step, look.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "simloop/model.hpp"
#include "simloop/run.hpp"

namespace simloop {

struct Contact {
  std::string geom1;  // geom names ("" if unnamed)
  std::string geom2;
  double dist = 0.0;  // signed distance; negative is penetration, m
  std::array<double, 3> pos{};  // contact point, world frame, m
};

class Sim {
 public:
  // A fresh state for `model` at t = 0, with mj_forward run so every read
  // is the true rest pose before the first step.
  explicit Sim(const Model& model);

  // Back to t = 0: state, ctrl, applied force and warnings all cleared.
  void reset();

  // Sim seconds per step. Changes this Sim's own copy of the model.
  void set_timestep(double timestep);
  [[nodiscard]] double timestep() const noexcept { return model_.timestep(); }

  // ctrl[0], the motor's command. Like everything written into mjData it
  // stays until overwritten. Throws InvalidArgument unless finite.
  void set_ctrl(double value);
  [[nodiscard]] double ctrl() const noexcept { return data_.get()->ctrl[0]; }

  // An external force on the box (N, world frame), added on top of physics
  // through xfrc_applied. IT PERSISTS: MuJoCo never clears it, so it acts on
  // every following step until clear_force(). Forgetting that is the
  // chapter's classic bug. Throws InvalidArgument unless finite.
  void apply_force(const std::array<double, 3>& force);
  void clear_force() noexcept;
  [[nodiscard]] std::array<double, 3> applied_force() const noexcept;

  // Advances n steps (n >= 1) with the current ctrl and force. With a
  // `control`, a long step can be stopped between chunks (Interrupted; the
  // steps already taken stay taken).
  void step(std::int64_t n = 1, RunControl* control = nullptr);

  [[nodiscard]] double time() const noexcept { return data_.get()->time; }
  [[nodiscard]] std::int64_t steps_taken() const noexcept { return steps_; }
  // The box's free joint: position (m), quaternion (w, x, y, z), linear
  // velocity (m/s, world) -- the state now, from qpos/qvel.
  [[nodiscard]] std::array<double, 3> box_position() const noexcept;
  [[nodiscard]] std::array<double, 4> box_quaternion() const noexcept;
  [[nodiscard]] std::array<double, 3> box_velocity() const noexcept;
  // The pusher's joint position and velocity.
  [[nodiscard]] double pusher_x() const noexcept;
  [[nodiscard]] double pusher_velocity() const noexcept;
  // The contacts MuJoCo found in its last collision pass.
  [[nodiscard]] std::vector<Contact> contacts() const;
  // Warnings MuJoCo raised since construction or reset.
  [[nodiscard]] std::vector<Warning> warnings() const;

  [[nodiscard]] const Model& model() const noexcept { return model_; }

 private:
  Model model_;
  Data data_;
  std::int64_t steps_ = 0;
  struct Counter;
  std::shared_ptr<Counter> counter_;
};

// Where the pusher body is for a given joint position: for a slide joint,
// rest_position + axis * (q - q0); for a hinge, rest_position. Used to draw
// the pusher from the trajectory's pusher_x (exact when the joint's parent
// does not move, as in the chapter's scene).
struct PusherTrack {
  std::array<double, 3> rest_position{};  // body position at qpos0, world
  std::array<double, 3> axis{};           // slide axis, world; zero for a hinge
  double q0 = 0.0;                        // the joint's qpos0
};
[[nodiscard]] PusherTrack pusher_track(const Model& model);

}  // namespace simloop
