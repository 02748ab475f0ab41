// Counting MuJoCo's warnings per run (internal to the library).
#pragma once

#include <mujoco/mujoco.h>

#include <cstdint>
#include <string>
#include <vector>

#include "simloop/rows.hpp"

namespace simloop::detail {

// Counts MuJoCo's warnings step by step. MuJoCo's own counters are not
// enough: a bad acceleration makes it reset mjData, counters included. So
// after each step we move the counts into our totals and zero them.
class WarningCounter {
 public:
  void after_step(mjData* d, std::int64_t step) noexcept {
    for (int i = 0; i < mjNWARNING; ++i) {
      mjWarningStat& stat = d->warning[i];
      if (stat.number == 0) continue;
      if (count_[i] == 0) first_step_[i] = step;
      count_[i] += stat.number;
      last_info_[i] = stat.lastinfo;
      stat.number = 0;
    }
  }
  [[nodiscard]] std::vector<Warning> warnings() const;

 private:
  // int64: a long run can warn in more than 2^31 steps (MuJoCo's own counter
  // is an int, but it is emptied into ours after every step).
  std::int64_t count_[mjNWARNING] = {};
  int last_info_[mjNWARNING] = {};
  std::int64_t first_step_[mjNWARNING] = {};
};

// Every name a run's warnings can carry: MuJoCo's (mjWARN_...) in MuJoCo's
// order, then simloop's own (simloop_DIVERGED). Tables of many runs give
// each its own column.
[[nodiscard]] std::vector<std::string> all_warning_names();

}  // namespace simloop::detail
