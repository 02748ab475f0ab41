#include "warning_counter.hpp"

#include <string>

#include "divergence.hpp"
#include "mujoco_compat.hpp"

namespace simloop::detail {

std::vector<Warning> WarningCounter::warnings() const {
  std::vector<Warning> out;
  for (int i = 0; i < mjNWARNING; ++i) {
    if (count_[i] == 0) continue;
    out.push_back({compat::warning_name(i), count_[i], first_step_[i], compat::warning_text(i, last_info_[i])});
  }
  return out;
}

std::vector<std::string> all_warning_names() {
  std::vector<std::string> names;
  for (int i = 0; i < compat::kWarningCount; ++i) names.emplace_back(compat::warning_name(i));
  names.emplace_back(kDivergedWarning);
  return names;
}

}  // namespace simloop::detail
