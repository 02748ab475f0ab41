// What the robustness tests share: the chapter's scene, loaded once, and a
// run of the chapter's of a given length.
#pragma once

#include <cstdint>

#include "simloop/model.hpp"
#include "simloop/run.hpp"

namespace test {

inline const simloop::Model& scene() {
  static const simloop::Model model = simloop::pusher_scene();
  return model;
}

inline simloop::RunConfig config_with(std::int64_t steps, std::int64_t record_every = 1) {
  simloop::RunConfig c;
  c.steps = steps;
  c.record_every = record_every;
  return c;
}

}  // namespace test
