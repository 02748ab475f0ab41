#include "simloop/shove.hpp"

#include <array>
#include <cmath>
#include <random>

#include "run_detail.hpp"
#include "simloop/errors.hpp"

namespace simloop {
namespace {

// [0, 1) from the top 53 bits of a 64-bit draw: what both numpy's
// next_double and our mt19937_64 rule compute.
double unit_double(std::uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

// ---- numpy's SeedSequence (numpy/random/bit_generator.pyx), for an integer
// entropy and no spawn key: the pool is 4 words of 32 bits.
constexpr std::uint32_t kInitA = 0x43b0d7e5u;
constexpr std::uint32_t kMultA = 0x931e8875u;
constexpr std::uint32_t kInitB = 0x8b51f9ddu;
constexpr std::uint32_t kMultB = 0x58f38dedu;
constexpr std::uint32_t kMixMultL = 0xca01f9ddu;
constexpr std::uint32_t kMixMultR = 0x4973f715u;
constexpr int kXShift = 16;
constexpr int kPoolSize = 4;

std::uint32_t hashmix(std::uint32_t value, std::uint32_t& hash_const) {
  value ^= hash_const;
  hash_const *= kMultA;
  value *= hash_const;
  value ^= value >> kXShift;
  return value;
}

std::uint32_t mix(std::uint32_t x, std::uint32_t y) {
  std::uint32_t result = kMixMultL * x - kMixMultR * y;
  result ^= result >> kXShift;
  return result;
}

// SeedSequence(seed).generate_state(4, np.uint64).
std::array<std::uint64_t, 4> seed_sequence_state(std::uint64_t seed) {
  // The integer as 32-bit words, least significant first; 0 is one word.
  std::uint32_t entropy[2] = {static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32)};
  const int entropy_words = (seed >> 32) != 0 ? 2 : 1;
  std::uint32_t pool[kPoolSize];
  std::uint32_t hash_const = kInitA;
  for (int i = 0; i < kPoolSize; ++i) pool[i] = hashmix(i < entropy_words ? entropy[i] : 0u, hash_const);
  for (int src = 0; src < kPoolSize; ++src) {
    for (int dst = 0; dst < kPoolSize; ++dst) {
      if (src != dst) pool[dst] = mix(pool[dst], hashmix(pool[src], hash_const));
    }
  }
  std::uint32_t words[8];
  hash_const = kInitB;
  for (int i = 0; i < 8; ++i) {
    std::uint32_t value = pool[i % kPoolSize] ^ hash_const;
    hash_const *= kMultB;
    value *= hash_const;
    value ^= value >> kXShift;
    words[i] = value;
  }
  // Read as little-endian uint64s.
  std::array<std::uint64_t, 4> state{};
  for (int k = 0; k < 4; ++k) state[k] = words[2 * k] | (std::uint64_t{words[2 * k + 1]} << 32);
  return state;
}

// ---- numpy's PCG64 (numpy/random/src/pcg64): a 128-bit LCG with the XSL-RR
// output. 128-bit arithmetic spelled out in 64-bit halves (portable C++).
struct U128 {
  std::uint64_t hi = 0, lo = 0;
};

U128 add(U128 a, U128 b) {
  U128 r{a.hi + b.hi, a.lo + b.lo};
  r.hi += r.lo < a.lo;
  return r;
}

// The full 128-bit product of two 64-bit numbers.
U128 mul_64x64(std::uint64_t a, std::uint64_t b) {
  const std::uint64_t a_lo = a & 0xffffffffu, a_hi = a >> 32, b_lo = b & 0xffffffffu, b_hi = b >> 32;
  const std::uint64_t lo_lo = a_lo * b_lo, hi_lo = a_hi * b_lo, lo_hi = a_lo * b_hi, hi_hi = a_hi * b_hi;
  const std::uint64_t cross = (lo_lo >> 32) + (hi_lo & 0xffffffffu) + lo_hi;
  return U128{hi_hi + (hi_lo >> 32) + (cross >> 32), (cross << 32) | (lo_lo & 0xffffffffu)};
}

// a * b modulo 2^128.
U128 mul(U128 a, U128 b) {
  U128 r = mul_64x64(a.lo, b.lo);
  r.hi += a.hi * b.lo + a.lo * b.hi;
  return r;
}

class Pcg64 {
 public:
  // pcg64_set_seed with numpy's split of the SeedSequence state: the first
  // two words are the initial state (high, low), the last two the stream.
  explicit Pcg64(std::uint64_t seed) {
    const std::array<std::uint64_t, 4> v = seed_sequence_state(seed);
    const U128 initstate{v[0], v[1]};
    const U128 initseq{v[2], v[3]};
    inc_ = U128{(initseq.hi << 1) | (initseq.lo >> 63), (initseq.lo << 1) | 1u};
    state_ = U128{};
    step();
    state_ = add(state_, initstate);
    step();
  }

  std::uint64_t next64() {
    step();
    const std::uint64_t x = state_.hi ^ state_.lo;
    const unsigned rot = static_cast<unsigned>(state_.hi >> 58);
    return (x >> rot) | (x << ((64u - rot) & 63u));
  }

  // numpy hands out a 64-bit draw in two 32-bit halves, low half first.
  std::uint32_t next32() {
    if (has_half_) {
      has_half_ = false;
      return half_;
    }
    const std::uint64_t next = next64();
    has_half_ = true;
    half_ = static_cast<std::uint32_t>(next >> 32);
    return static_cast<std::uint32_t>(next);
  }

 private:
  // PCG_DEFAULT_MULTIPLIER_128.
  static constexpr U128 kMultiplier{2549297995355413924ull, 4865540595714422341ull};
  void step() { state_ = add(mul(state_, kMultiplier), inc_); }

  U128 state_, inc_;
  bool has_half_ = false;
  std::uint32_t half_ = 0;
};

// numpy's buffered_bounded_lemire_uint32 for a range [0, rng]: integers(0, n)
// with rng = n - 1.
std::uint32_t bounded_lemire(Pcg64& g, std::uint32_t rng) {
  const std::uint64_t rng_excl = std::uint64_t{rng} + 1;
  std::uint64_t m = std::uint64_t{g.next32()} * rng_excl;
  auto leftover = static_cast<std::uint32_t>(m);
  if (leftover < rng_excl) {
    const auto threshold = static_cast<std::uint32_t>((0xffffffffull - rng) % rng_excl);
    while (leftover < threshold) {
      m = std::uint64_t{g.next32()} * rng_excl;
      leftover = static_cast<std::uint32_t>(m);
    }
  }
  return static_cast<std::uint32_t>(m >> 32);
}

}  // namespace

std::string_view rng_name(ShoveRng rng) noexcept { return rng == ShoveRng::kNumpy ? "numpy" : "mt19937_64"; }

std::string_view rng_description(ShoveRng rng) noexcept {
  return rng == ShoveRng::kNumpy ? "numpy default_rng (PCG64)" : "std::mt19937_64";
}

std::optional<ShoveRng> parse_rng(std::string_view name) noexcept {
  if (name == "mt19937_64") return ShoveRng::kMt19937_64;
  if (name == "numpy") return ShoveRng::kNumpy;
  return std::nullopt;
}

ShoveRng rng_named(std::string_view name) {
  const std::optional<ShoveRng> rng = parse_rng(name);
  if (!rng) throw InvalidArgument("rng must be 'mt19937_64' or 'numpy', got '" + std::string(name) + "'");
  return *rng;
}

namespace {

class NumpyDraws final : public Draws {
 public:
  explicit NumpyDraws(std::uint64_t seed) : generator_(seed) {}
  double uniform(double low, double high) override { return low + (high - low) * unit_double(generator_.next64()); }
  double sign() override {
    const double choices[2] = {-1.0, 1.0};
    return choices[bounded_lemire(generator_, 1)];  // choice([-1.0, 1.0])
  }

 private:
  Pcg64 generator_;
};

class Mt19937Draws final : public Draws {
 public:
  explicit Mt19937Draws(std::uint64_t seed) : generator_(seed) {}
  double uniform(double low, double high) override { return low + (high - low) * unit_double(generator_()); }
  double sign() override { return unit_double(generator_()) < 0.5 ? -1.0 : 1.0; }

 private:
  std::mt19937_64 generator_;
};

}  // namespace

double standard_normal(Draws& draws) {
  for (;;) {
    const double u = draws.uniform(-1.0, 1.0);
    const double v = draws.uniform(-1.0, 1.0);
    const double s = u * u + v * v;
    if (s > 0.0 && s < 1.0) return u * std::sqrt(-2.0 * std::log(s) / s);
  }
}

std::unique_ptr<Draws> make_draws(std::uint64_t seed, ShoveRng rng) {
  if (rng == ShoveRng::kNumpy) return std::make_unique<NumpyDraws>(seed);
  return std::make_unique<Mt19937Draws>(seed);
}

Shove draw_shove(std::uint64_t seed, std::int64_t num_steps, ShoveRng rng) {
  detail::check_schedule_run(num_steps, 1);  // a run's steps
  Shove shove;
  // uniform(6.0, 12.0), then the sign: numpy's choice([-1.0, 1.0]), or u < 0.5.
  if (rng == ShoveRng::kNumpy) {
    NumpyDraws draws(seed);
    shove.newtons = draws.uniform(6.0, 12.0);
    shove.sign = draws.sign();
  } else {
    Mt19937Draws draws(seed);
    shove.newtons = draws.uniform(6.0, 12.0);
    shove.sign = draws.sign();
  }
  shove.start_step = num_steps / 2;
  shove.num_steps = kShoveSteps;
  shove.rng = rng;
  return shove;
}

}  // namespace simloop
