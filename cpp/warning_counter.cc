#include "warning_counter.hpp"

#include <cstdio>
#include <iterator>
#include <string>

#include "divergence.hpp"

namespace simloop::detail {
namespace {

// MuJoCo 2.2's texts for its warnings (mju_warningText), rebuilt here because
// that function writes a shared static buffer and batches step in threads.
std::string warning_message(int warning, int info) {
  static constexpr const char* kFormats[mjNWARNING] = {
      "Inertia matrix is too close to singular at DOF %d. Check model.",
      "Pre-allocated contact buffer is full. Increase nconmax above %d.",
      "Pre-allocated constraint buffer is full. Increase njmax above %d.",
      "Pre-allocated visual geom buffer is full. Increase maxgeom above %d.",
      "Nan, Inf or huge value in QPOS at DOF %d. The simulation is unstable.",
      "Nan, Inf or huge value in QVEL at DOF %d. The simulation is unstable.",
      "Nan, Inf or huge value in QACC at DOF %d. The simulation is unstable.",
      "Nan, Inf or huge value in CTRL at ACTUATOR %d. The simulation is unstable."};
  char text[160];
  std::snprintf(text, sizeof text, kFormats[warning], info);
  return text;
}

constexpr const char* kWarningNames[mjNWARNING] = {
    "mjWARN_INERTIA", "mjWARN_CONTACTFULL", "mjWARN_CNSTRFULL", "mjWARN_VGEOMFULL",
    "mjWARN_BADQPOS", "mjWARN_BADQVEL", "mjWARN_BADQACC", "mjWARN_BADCTRL"};

}  // namespace

std::vector<Warning> WarningCounter::warnings() const {
  std::vector<Warning> out;
  for (int i = 0; i < mjNWARNING; ++i) {
    if (count_[i] == 0) continue;
    out.push_back({kWarningNames[i], count_[i], first_step_[i], warning_message(i, last_info_[i])});
  }
  return out;
}

std::vector<std::string> all_warning_names() {
  std::vector<std::string> names(std::begin(kWarningNames), std::end(kWarningNames));
  names.emplace_back(kDivergedWarning);
  return names;
}

}  // namespace simloop::detail
