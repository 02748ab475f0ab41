// The shove: the chapter's mid-run sideways push on the box, and the only
// random thing in a run.
#pragma once

#include <cstdint>

namespace simloop {

// Steps the shove lasts: 0.1 s at the default timestep.
inline constexpr std::int64_t kShoveSteps = 50;

struct Shove {
  double newtons = 0.0;       // strength, uniform in [6, 12): friction resists with ~5 N
  double sign = 1.0;          // +1: +y, -1: -y (sideways, across the pusher's line)
  std::int64_t start_step = 0;  // steps // 2
  std::int64_t num_steps = kShoveSteps;

  [[nodiscard]] double force_y() const noexcept { return sign * newtons; }
  // True on the steps the shove acts, [start_step, start_step + num_steps).
  [[nodiscard]] bool acts_at(std::int64_t step) const noexcept {
    return step >= start_step && step < start_step + num_steps;
  }
};

// Draws the shove for a run of `num_steps` steps from std::mt19937_64 seeded
// with `seed`. The engine is fully specified by the C++ standard, but its
// distributions are not, so the draws are spelled out here and are the same
// on every standard library: u = (g() >> 11) * 2^-53 in [0, 1);
// newtons = 6 + 6 * u1; sign = u2 < 0.5 ? -1 : +1. The shove is drawn even
// when a run does not apply it, so the seed changes nothing else.
[[nodiscard]] Shove draw_shove(std::uint64_t seed, std::int64_t num_steps) noexcept;

}  // namespace simloop
