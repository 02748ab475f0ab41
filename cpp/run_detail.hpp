// Internals shared by the library's loops.
#pragma once

#include "simloop/run.hpp"

namespace simloop::detail {

// run() without announcing its steps to the control: a batch announces all
// of its runs' steps up front, so progress has its true total from the start.
[[nodiscard]] RunResult run_counted_elsewhere(const Model& model, const RunConfig& config, Data& workspace,
                                              RowSink* sink, RunControl* control);

// Tests only: from now on run_batch can start at most `threads` more threads
// (as under a process limit, RLIMIT_NPROC); a negative count lifts the limit.
void limit_thread_starts_for_testing(int threads) noexcept;

}  // namespace simloop::detail
