// A run streamed into an output folder: trajectory.csv written as the loop
// steps (memory bounded however long the run), then metrics.json, put in
// place by commit() together with what else the caller made of the run (a
// recording's files), or (an error, a stop, never committed) none of them.
// Both commands' runs are these.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "simloop/control.hpp"
#include "simloop/model.hpp"
#include "simloop/output.hpp"
#include "simloop/rows.hpp"
#include "simloop/run.hpp"
#include "simloop/run_record.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"

namespace simloop {

// A finished run's outputs, written beside their places and not yet in them.
// Destroyed uncommitted, it removes its temporary files.
class PendingOutputs {
 public:
  PendingOutputs(std::unique_ptr<OutputWriter> writer, std::string metrics)
      : writer_(std::move(writer)), metrics_(std::move(metrics)) {}
  // metrics.json and trajectory.csv put in place together with `also`, all
  // or none (commit_together); Interrupted if `control`'s stop was asked.
  OutputFiles commit(const RunControl* control = nullptr, const std::vector<PendingFile*>& also = {}) {
    return writer_->commit(metrics_, control, also);
  }

 private:
  std::unique_ptr<OutputWriter> writer_;
  std::string metrics_;
};

// The chapter's run into `out` (a prepared folder). `drawing`, if given,
// gets its rows too.
[[nodiscard]] std::pair<RunResult, PendingOutputs> run_to_folder(const Model& model, const RunConfig& config,
                                                                 const std::filesystem::path& out,
                                                                 RowSink* drawing = nullptr,
                                                                 RunControl* control = nullptr);
// A scenario's run into `out`. `drawing`, if given, gets its rows with every
// moving body's pose after them, as run_scenario_drawn gives them.
[[nodiscard]] std::pair<RunRecord, PendingOutputs> run_to_folder(const Model& scene, const Scenario& scenario,
                                                                 const ScenarioConfig& config,
                                                                 const std::filesystem::path& out,
                                                                 RowSink* drawing = nullptr,
                                                                 RunControl* control = nullptr);

}  // namespace simloop
