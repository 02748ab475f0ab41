#include "simloop/folder_run.hpp"

namespace simloop {
namespace {

std::vector<PendingFile*> files_of(RunDrawing* drawing) {
  return drawing ? drawing->files() : std::vector<PendingFile*>{};
}

}  // namespace

std::pair<RunResult, OutputFiles> run_to_folder(const Model& model, const RunConfig& config,
                                                const std::filesystem::path& out, RunDrawing* drawing,
                                                RunControl* control) {
  OutputWriter writer(out);
  Data workspace(model);
  TeeRows rows(writer.trajectory(), drawing ? &drawing->rows() : nullptr);
  RunResult result = run(model, config, workspace, &rows, control);
  if (drawing) drawing->finish(result);
  OutputFiles files = writer.commit(result.metrics, control, files_of(drawing));
  return {std::move(result), std::move(files)};
}

std::pair<RunRecord, OutputFiles> run_to_folder(const Model& scene, const Scenario& scenario,
                                                const ScenarioConfig& config, const std::filesystem::path& out,
                                                RunDrawing* drawing, RunControl* control) {
  OutputWriter writer(out);
  // A drawing draws every moving body: the run hands it their poses too.
  RunRecord result = drawing
                         ? run_scenario_drawn(scene, scenario, config, writer.trajectory(), drawing->rows(), control)
                         : run_scenario(scene, scenario, config, nullptr, &writer.trajectory(), control);
  if (drawing) drawing->finish(result);
  OutputFiles files = writer.commit(metrics_json(result), control, files_of(drawing));
  return {std::move(result), std::move(files)};
}

}  // namespace simloop
