// A run streamed into an output folder: trajectory.csv written as the loop
// steps (memory bounded however long the run), then metrics.json, put in
// place together with a drawing's files, or (an error, a stop) none of them.
// Both commands' runs and Python's run_to_files are these.
#pragma once

#include <filesystem>
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

// What else a run into a folder feeds (a recording): its rows go to rows()
// too (a scenario's with every moving body's pose after them, as
// run_scenario_drawn gives them); finish(result) is called once the run is
// done, before the outputs are put in place together with files().
class RunDrawing {
 public:
  virtual ~RunDrawing() = default;
  [[nodiscard]] virtual RowSink& rows() = 0;
  [[nodiscard]] virtual std::vector<PendingFile*> files() = 0;
  virtual void finish(const RunResult& result) = 0;  // the chapter's run
  virtual void finish(const RunRecord& result) = 0;  // a scenario's
};

// The chapter's run into `out` (a prepared folder), and where its files went.
[[nodiscard]] std::pair<RunResult, OutputFiles> run_to_folder(const Model& model, const RunConfig& config,
                                                              const std::filesystem::path& out,
                                                              RunDrawing* drawing = nullptr,
                                                              RunControl* control = nullptr);
// A scenario's run into `out`.
[[nodiscard]] std::pair<RunRecord, OutputFiles> run_to_folder(const Model& scene, const Scenario& scenario,
                                                              const ScenarioConfig& config,
                                                              const std::filesystem::path& out,
                                                              RunDrawing* drawing = nullptr,
                                                              RunControl* control = nullptr);

}  // namespace simloop
