// What the chapter's run (run.cc) shares with its batch (batch.cc).
#pragma once

#include "simloop/control.hpp"
#include "simloop/run.hpp"

namespace simloop::detail {

// run() without announcing its steps to the control: a batch announces all
// of its runs' steps up front, so progress has its true total from the start.
[[nodiscard]] RunResult run_counted_elsewhere(const Model& model, const RunConfig& config, Data& workspace,
                                              RowSink* sink, RunControl* control);

}  // namespace simloop::detail
