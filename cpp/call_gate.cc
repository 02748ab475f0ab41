#include "simloop/call_gate.hpp"

#include <string>

#include "simloop/control.hpp"
#include "simloop/errors.hpp"

namespace simloop {

bool wait_in_slices(const std::function<bool(std::chrono::milliseconds)>& wait_slice,
                    const std::function<void()>& between, std::optional<double> timeout) {
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    if (wait_slice(RunControl::kPollInterval)) return true;
    between();
    if (timeout && std::chrono::steady_clock::now() - start >= std::chrono::duration<double>(*timeout)) return false;
  }
}

void CallGate::refuse_reentry(const char* what) const {
  if (holder_.load(std::memory_order_relaxed) == std::this_thread::get_id()) {
    throw InvalidArgument(std::string(what) +
                          " in the middle of a call on this thread (a signal handler or progress callback called "
                          "it); call it after that call returns");
  }
}

}  // namespace simloop
