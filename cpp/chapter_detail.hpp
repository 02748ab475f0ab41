// What the chapter's view (run.cc) shares with the sweep and the bindings.
#pragma once

#include <string>
#include <vector>

#include "simloop/control.hpp"
#include "simloop/run.hpp"

namespace simloop::detail {

// run() without announcing its steps to the control: a batch announces all
// of its runs' steps up front, so progress has its true total from the start.
[[nodiscard]] RunResult run_counted_elsewhere(const Model& model, const RunConfig& config, Data& workspace,
                                              RowSink* sink, RunControl* control);

// The chapter's runs as one batch of its scenario (run_scenario_batch): result
// i is bitwise run(model, configs[i]), at any thread count. With `sinks` (one
// per config, none null), run i's rows go to sinks[i] and are not kept. All
// configs are checked before any run starts (InvalidArgument naming the
// config's index), and kept rows must fit together (check_kept_rows).
[[nodiscard]] std::vector<RunResult> run_chapter_batch(const Model& model, const std::vector<RunConfig>& configs,
                                                       const std::vector<RowSink*>& sinks, int threads = 0,
                                                       RunControl* control = nullptr);

// Actuator 0's joint, the chapter's pusher, by the name that stems its
// columns ("<name>_pos", "<name>_vel") in a run of chapter_scenario(model).
[[nodiscard]] std::string pusher_joint_name(const Model& model);

}  // namespace simloop::detail
