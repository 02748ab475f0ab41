#include "simloop/folder_run.hpp"

namespace simloop {

std::pair<RunResult, PendingOutputs> run_to_folder(const Model& model, const RunConfig& config,
                                                   const std::filesystem::path& out, RowSink* drawing,
                                                   RunControl* control) {
  auto writer = std::make_unique<OutputWriter>(out);
  Data workspace(model);
  TeeRows rows(writer->trajectory(), drawing);
  RunResult result = run(model, config, workspace, &rows, control);
  std::string metrics = metrics_json(result.metrics);
  return {std::move(result), PendingOutputs(std::move(writer), std::move(metrics))};
}

std::pair<RunRecord, PendingOutputs> run_to_folder(const Model& scene, const Scenario& scenario,
                                                   const ScenarioConfig& config, const std::filesystem::path& out,
                                                   RowSink* drawing, RunControl* control) {
  auto writer = std::make_unique<OutputWriter>(out);
  // A drawing draws every moving body: the run hands it their poses too.
  RunRecord result = drawing ? run_scenario_drawn(scene, scenario, config, writer->trajectory(), *drawing, control)
                             : run_scenario(scene, scenario, config, nullptr, &writer->trajectory(), control);
  std::string metrics = metrics_json(result);
  return {std::move(result), PendingOutputs(std::move(writer), std::move(metrics))};
}

}  // namespace simloop
