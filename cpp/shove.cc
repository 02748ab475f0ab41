#include "simloop/shove.hpp"

#include <random>

namespace simloop {

Shove draw_shove(std::uint64_t seed, std::int64_t num_steps) noexcept {
  std::mt19937_64 generator(seed);
  const auto uniform01 = [&generator] {
    return static_cast<double>(generator() >> 11) * 0x1.0p-53;
  };
  Shove shove;
  shove.newtons = 6.0 + 6.0 * uniform01();
  shove.sign = uniform01() < 0.5 ? -1.0 : 1.0;
  shove.start_step = num_steps / 2;
  shove.num_steps = kShoveSteps;
  return shove;
}

}  // namespace simloop
