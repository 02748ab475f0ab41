// The shove: the chapter's mid-run sideways push on the box, and the only
// random thing in a run.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>

namespace simloop {

// Steps the shove lasts: 0.1 s at the default timestep.
inline constexpr std::int64_t kShoveSteps = 50;

// The generator that draws the shove from the seed.
enum class ShoveRng {
  // std::mt19937_64 seeded with the seed: the default, fixed by the C++
  // standard, with the draws spelled out below.
  kMt19937_64,
  // The chapter's np.random.default_rng(seed): PCG64 seeded through numpy's
  // SeedSequence, then uniform(6.0, 12.0) and choice([-1.0, 1.0]) exactly as
  // numpy computes them. Implemented here; numpy is not needed at run time.
  kNumpy,
};

// "mt19937_64" or "numpy": the names --rng and rng= take.
[[nodiscard]] std::string_view rng_name(ShoveRng rng) noexcept;
// Who drew it, for people: "std::mt19937_64" or "numpy default_rng (PCG64)".
[[nodiscard]] std::string_view rng_description(ShoveRng rng) noexcept;
// The generator named `name` (as rng_name spells it), or nothing.
[[nodiscard]] std::optional<ShoveRng> parse_rng(std::string_view name) noexcept;
// The same, or InvalidArgument "rng must be 'mt19937_64' or 'numpy', got '...'".
[[nodiscard]] ShoveRng rng_named(std::string_view name);

// A run's one source of randomness: the draws a scenario's random
// disturbances make, in order (the chapter's shove is one such disturbance).
class Draws {
 public:
  virtual ~Draws() = default;
  [[nodiscard]] virtual double uniform(double low, double high) = 0;  // [low, high): low + (high - low) * u
  [[nodiscard]] virtual double sign() = 0;                            // -1 or +1
};

// A standard normal value from `draws`, the same on every standard library
// (std::normal_distribution is not): Marsaglia's polar method over the
// generator's uniform draws, u = uniform(-1, 1), v = uniform(-1, 1), drawn
// again (both) until 0 < s = u * u + v * v < 1; then u * sqrt(-2 log(s) / s).
// v's twin value is not kept: each call starts from fresh draws. (Only log
// is the C library's, which IEEE 754 does not pin to the bit.)
[[nodiscard]] double standard_normal(Draws& draws);

// The generator `rng` seeded with `seed`, drawing as described at draw_shove.
[[nodiscard]] std::unique_ptr<Draws> make_draws(std::uint64_t seed, ShoveRng rng = ShoveRng::kMt19937_64);

struct Shove {
  double newtons = 0.0;         // strength, uniform in [6, 12): friction resists with ~5 N
  double sign = 1.0;            // +1: +y, -1: -y (sideways, across the pusher's line)
  std::int64_t start_step = 0;  // steps // 2
  std::int64_t num_steps = kShoveSteps;
  ShoveRng rng = ShoveRng::kMt19937_64;  // the generator that drew it

  [[nodiscard]] double force_y() const noexcept { return sign * newtons; }
  // True on the steps the shove acts, [start_step, start_step + num_steps).
  [[nodiscard]] bool acts_at(std::int64_t step) const noexcept {
    return step >= start_step && step < start_step + num_steps;
  }
};

// Draws the shove for a run of `num_steps` steps from `seed` with `rng`. The
// shove is drawn even when a run does not apply it, so the seed changes
// nothing else.
//
// kMt19937_64: the engine is fully specified by the C++ standard, but its
// distributions are not, so the draws are spelled out here and are the same
// on every standard library: u = (g() >> 11) * 2^-53 in [0, 1);
// newtons = 6 + 6 * u1; sign = u2 < 0.5 ? -1 : +1.
//
// kNumpy: numpy's PCG64 (XSL-RR 128/64) seeded by SeedSequence(seed);
// newtons = 6 + 6 * ((next64() >> 11) * 2^-53), numpy's uniform(6.0, 12.0);
// sign from numpy's choice([-1.0, 1.0]): integers(0, 2) by Lemire's method
// on the next 32-bit draw (the low half of the next 64-bit output).
// num_steps: a run's, 1 to kMaxSteps (InvalidArgument otherwise).
[[nodiscard]] Shove draw_shove(std::uint64_t seed, std::int64_t num_steps, ShoveRng rng = ShoveRng::kMt19937_64);

}  // namespace simloop
