#include "simloop/control.hpp"

#include "simloop/errors.hpp"

namespace simloop {

void RunControl::poll_now() {
  last_poll_ = std::chrono::steady_clock::now();
  if (!poll_ || stop_requested()) return;
  try {
    poll_(steps_done(), steps_total());
  } catch (...) {
    poll_failure_ = std::current_exception();
    request_stop();
  }
}

void RunControl::advance(std::int64_t steps) {
  done_.fetch_add(steps, std::memory_order_relaxed);
  if (poll_ && std::this_thread::get_id() == owner_ && std::chrono::steady_clock::now() - last_poll_ >= kPollInterval) {
    poll_now();
  }
  if (stop_requested() || batch_abandoned()) throw Interrupted("interrupted");
}

void RunControl::check() {
  if (std::this_thread::get_id() == owner_) poll_now();
  if (stop_requested()) throw Interrupted("interrupted");
}

}  // namespace simloop
