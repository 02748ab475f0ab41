#include "simloop/scenario_run.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <list>
#include <map>
#include <optional>
#include <variant>

#include "json_text.hpp"
#include "run_detail.hpp"
#include "simloop/batch.hpp"
#include "simloop/chapter_scene.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"
#include "simloop/output.hpp"
#include "simloop/scene_params.hpp"

namespace simloop {

Model load_scene(const Scenario& scenario) {
  if (scenario.scene.empty()) return pusher_scene();
  return Model::from_file(scenario.scene.string());
}

namespace {

// A run of a scenario, made ready on its model: names resolved, inputs
// drawn, its recorder laid out (the columns).
struct PreparedRun {
  ResolvedScenario resolved;
  Schedule schedule;
  std::optional<Recorder> recorder;
};

PreparedRun prepare(const Model& model, const Scenario& scenario, const ScenarioConfig& config,
                    bool with_recorder = true) {
  const Scenario effective = detail::configured_scenario(scenario, config);
  PreparedRun run;
  run.resolved = resolve(effective, model.get());
  const std::unique_ptr<Draws> draws = make_draws(config.seed, config.rng);
  run.schedule = build_schedule(run.resolved, effective, model.timestep(), *draws);
  if (with_recorder) run.recorder.emplace(model.get(), run.resolved, run.schedule, config.audit_energy);
  return run;
}

// The bodies a run's schedule pushes, in order: with the run's shape, what its recorder's columns depend on.
std::vector<int> pushed_bodies(const Schedule& schedule) {
  std::vector<int> out;
  for (const Schedule::Force& f : schedule.forces) out.push_back(f.body);
  return out;
}

RunRecord labelled(RunRecord result, const mjModel* m, const Scenario& scenario, const ScenarioConfig& config) {
  result.name = scenario.name;
  result.seed = config.seed;
  result.rng = std::string(rng_name(config.rng));
  result.perturb = config.perturb;
  for (const Schedule::Force& f : result.schedule.forces) {
    result.disturbed_bodies.push_back(object_name(m, mjOBJ_BODY, f.body));
  }
  return result;
}

// A run on `model` (scene.for_run's already): prepared, then stepped in
// `workspace`, which need not be reset if fresh.
RunRecord run_watched(const Model& model, const Scenario& scenario, const ScenarioConfig& config, Data& workspace,
                      RowSink* sink, RunControl* control, const RunInputs& inputs,
                      const std::vector<detail::StepObserver*>& watching, bool announce) {
  if (!workspace.fits(model)) throw InvalidArgument("workspace Data was made for a model of another size");
  const PreparedRun run = prepare(model, scenario, config);
  // The run's own scene parameters ([reset] params), on its own copy.
  const Model with_params = with_scene_params(model, run.schedule.start.params);
  const bool d_is_reset = workspace.fresh_for(with_params);  // before get(), which ends that
  mjData* d = workspace.get();
  const mjModel* m = with_params.get();
  if (announce && control && run.schedule.steps >= 1 && run.schedule.steps <= kMaxSteps) {
    control->add_total(run.schedule.steps);
  }
  return labelled(detail::run_schedule_counted_elsewhere(m, d, *run.recorder, run.schedule, config.record_every, sink,
                                                         control, inputs, watching, d_is_reset),
                  m, scenario, config);
}

}  // namespace

Scenario detail::configured_scenario(const Scenario& scenario, const ScenarioConfig& config) {
  Scenario effective = scenario;
  if (config.steps) effective.length = When::steps(*config.steps);
  if (!config.perturb) effective.disturbances.clear();
  return effective;
}

double run_timestep(const Model& scene, const Scenario& scenario, const ScenarioConfig& config) {
  return config.timestep.value_or(scenario.timestep.value_or(scene.timestep()));
}

void check_scenario(const Model& scene, const Scenario& scenario, const ScenarioConfig& config) {
  (void)scenario_columns(scene, scenario, config);
}

std::vector<std::string> scenario_columns(const Model& scene, const Scenario& scenario, const ScenarioConfig& config) {
  const Model model = scene.for_run(run_timestep(scene, scenario, config), config.audit_energy);
  const PreparedRun run = prepare(model, scenario, config);  // names, schedule, columns
  detail::check_schedule_run(run.schedule.steps, config.record_every);
  std::vector<std::string> names;
  for (const Column& c : run.recorder->columns()) names.push_back(c.name);
  return names;
}

RunRecord run_scenario(const Model& scene, const Scenario& scenario, const ScenarioConfig& config, Data* workspace,
                       RowSink* sink, RunControl* control, const RunInputs& inputs) {
  const Model model = scene.for_run(run_timestep(scene, scenario, config), config.audit_energy);
  std::optional<Data> own;
  if (workspace == nullptr) workspace = &own.emplace(model);
  return run_watched(model, scenario, config, *workspace, sink, control, inputs, {}, true);
}

RunRecord detail::run_scenario_watched(const Model& scene, const Scenario& scenario, const ScenarioConfig& config,
                                       Data& workspace, RowSink* sink, RunControl* control,
                                       const std::vector<StepObserver*>& watching, bool announce) {
  return run_watched(scene.for_run(run_timestep(scene, scenario, config), config.audit_energy), scenario, config,
                     workspace, sink, control, {}, watching, announce);
}

std::vector<RunRecord> run_scenario_batch(const Model& scene, const Scenario& scenario,
                                          const std::vector<ScenarioConfig>& configs, int threads, RunControl* control,
                                          const std::vector<RunInputs>& inputs, bool keep_rows) {
  DiscardRows discard;  // stateless: every worker may write to it at once
  return run_scenario_batch(scene, scenario, configs,
                            std::vector<RowSink*>(configs.size(), keep_rows ? nullptr : &discard), threads, control,
                            inputs);
}

std::vector<RunRecord> run_scenario_batch(const Model& scene, const Scenario& scenario,
                                          const std::vector<ScenarioConfig>& configs,
                                          const std::vector<RowSink*>& sinks, int threads, RunControl* control,
                                          const std::vector<RunInputs>& inputs) {
  return detail::run_scenario_batch_watched(scene, scenario, configs, sinks, threads, control, inputs, {});
}

std::vector<RunRecord> detail::run_scenario_batch_watched(const Model& scene, const Scenario& scenario,
                                                          const std::vector<ScenarioConfig>& configs,
                                                          const std::vector<RowSink*>& sinks, int threads,
                                                          RunControl* control, const std::vector<RunInputs>& inputs,
                                                          const std::vector<std::vector<StepObserver*>>& watching) {
  std::vector<RunRecord> results(configs.size());
  for_each_scenario_run(scene, scenario, configs, sinks, threads, control, inputs, watching,
                        [&](std::size_t i, RunRecord&& record) { results[i] = std::move(record); });
  return results;
}

void detail::for_each_scenario_run(const Model& scene, const Scenario& scenario,
                                   const std::vector<ScenarioConfig>& configs, const std::vector<RowSink*>& sinks,
                                   int threads, RunControl* control, const std::vector<RunInputs>& inputs,
                                   const std::vector<std::vector<StepObserver*>>& watching,
                                   const std::function<void(std::size_t i, RunRecord&& record)>& done) {
  if (sinks.size() != configs.size()) {
    throw InvalidArgument("sinks must hold one per config (" + std::to_string(configs.size()) + "), got " +
                          std::to_string(sinks.size()));
  }
  detail::check_threads(threads);
  if (!inputs.empty() && inputs.size() != configs.size()) {
    throw InvalidArgument("inputs: one RunInputs per config, got " + std::to_string(inputs.size()) + " for " +
                          std::to_string(configs.size()) + " configs");
  }
  const RunInputs no_inputs;
  const auto inputs_of = [&](std::size_t i) -> const RunInputs& { return inputs.empty() ? no_inputs : inputs[i]; };
  if (!watching.empty() && watching.size() != configs.size()) {
    throw InvalidArgument("watching: one list of observers per config, got " + std::to_string(watching.size()) +
                          " for " + std::to_string(configs.size()) + " configs");
  }
  // Up front, on this thread: one model per distinct timestep (the model is
  // frozen while the workers share it), every run's checks, and the memory
  // all the kept rows will take together. What the checks need (names,
  // length, columns) does not depend on the seed, so a run is prepared here
  // once per distinct configuration but its seed; each run is drawn and
  // prepared again by the worker that runs it and dropped with it, so the
  // batch holds no more runs than it has workers.
  std::list<std::pair<std::pair<double, bool>, Model>> models;  // stable addresses for model_of
  // What a run prepared on a model shows, and its recorder: made once per
  // batch, it only reads while runs record, so every worker shares it (a
  // recorder was a third of a short metrics-only run's cost beyond its steps).
  struct Shape {
    const Model* model;
    bool perturb;
    std::optional<std::int64_t> steps;
    std::int64_t schedule_steps;
    int width;
    std::vector<int> pushed;
    std::optional<Recorder> recorder;
  };
  std::list<Shape> shapes;  // stable addresses for shape_of
  std::vector<const Shape*> shape_of;
  std::vector<const Model*> model_of;
  std::vector<std::int64_t> steps;
  std::vector<KeptRows> kept;
  for (std::size_t i = 0; i < configs.size(); ++i) {
    const ScenarioConfig& config = configs[i];
    detail::check_run(i, [&] {
      const std::pair<double, bool> key{run_timestep(scene, scenario, config), config.audit_energy};
      auto it = std::find_if(models.begin(), models.end(), [&](const auto& m) { return m.first == key; });
      if (it == models.end()) it = models.emplace(models.end(), key, scene.for_run(key.first, key.second));
      const Model* model = &it->second;
      auto shape = std::find_if(shapes.begin(), shapes.end(), [&](const Shape& s) {
        return s.model == model && s.perturb == config.perturb && s.steps == config.steps;
      });
      if (shape == shapes.end()) {
        PreparedRun run = prepare(*model, scenario, config);
        shape = shapes.insert(shapes.end(), {model, config.perturb, config.steps, run.schedule.steps,
                                             run.recorder->width(), pushed_bodies(run.schedule), std::nullopt});
        shape->recorder.emplace(std::move(*run.recorder));
      }
      shape_of.push_back(&*shape);
      model_of.push_back(model);
      steps.push_back(shape->schedule_steps);
      detail::check_schedule_run(shape->schedule_steps, config.record_every);
      check_inputs(model->get(), inputs_of(i), shape->schedule_steps);
      if (sinks[i] == nullptr) kept.push_back({shape->schedule_steps, config.record_every, shape->width});
    });
  }
  if (!kept.empty()) check_kept_rows(kept);

  detail::run_jobs(scene, configs.size(), threads, steps, control, [&](std::size_t i, Data& data, RunControl& ctl) {
    const Shape& shape = *shape_of[i];
    PreparedRun run = prepare(*model_of[i], scenario, configs[i], false);
    if (pushed_bodies(run.schedule) != shape.pushed) {  // (not the shape's columns: its own recorder)
      run.recorder.emplace(model_of[i]->get(), run.resolved, run.schedule, configs[i].audit_energy);
    }
    const Recorder& recorder = run.recorder ? *run.recorder : *shape.recorder;
    // A run with scene parameters of its own ([reset] params) runs on its own
    // copy, made here rather than up front: one at a time per worker.
    const Model with_params = with_scene_params(*model_of[i], run.schedule.start.params);
    const mjModel* m = with_params.get();
    done(i, labelled(detail::run_schedule_counted_elsewhere(
                         m, data.get(), recorder, run.schedule, configs[i].record_every, sinks[i], &ctl, inputs_of(i),
                         watching.empty() ? std::vector<StepObserver*>{} : watching[i]),
                     m, scenario, configs[i]));
  });
}

// ---------------------------------------------------------------------------
// Drawing a run.

namespace {

std::vector<int> moving_body_ids(const mjModel* m) {
  std::vector<int> out;
  for (int b = 1; b < m->nbody; ++b) {
    if (body_can_move(m, b) && m->body_geomnum[b] > 0) out.push_back(b);
  }
  return out;
}

}  // namespace

std::vector<std::string> moving_bodies(const Model& scene) {
  const mjModel* m = scene.get();
  std::vector<std::string> out;
  for (int b : moving_body_ids(m)) {
    out.push_back(object_name(m, mjOBJ_BODY, b));
  }
  return out;
}

namespace {

// Splits the rows of a run that records the moving bodies and every joint
// too: the trajectory's own columns go to `sink`; those followed by each
// moving body's pose and then the positions of every joint (qpos, in
// order: what a picture of the row's state needs) go to `drawing`.
class DrawingSplit final : public RowSink {
 public:
  DrawingSplit(std::vector<Column> columns, std::vector<std::string> bodies, std::vector<std::string> positions,
               RowSink& sink, RowSink& drawing)
      : columns_(std::move(columns)),
        bodies_(std::move(bodies)),
        positions_(std::move(positions)),
        sink_(sink),
        drawing_(drawing) {}
  void describe(const std::vector<Column>& wide) override {
    std::map<std::string, std::size_t> index;
    for (std::size_t c = 0; c < wide.size(); ++c) index[wide[c].name] = c;
    for (const Column& c : columns_) picks_.push_back(index.at(c.name));
    std::vector<Column> drawn = columns_;
    const std::map<std::string, std::size_t> poses = recorded_bodies(wide);
    for (const std::string& body : bodies_) {
      for (int k = 0; k < 7; ++k) {
        pose_picks_.push_back(poses.at(body) + static_cast<std::size_t>(k));
        drawn.push_back(wide[poses.at(body) + static_cast<std::size_t>(k)]);
      }
    }
    for (const std::string& position : positions_) {
      pose_picks_.push_back(index.at(position));
      drawn.push_back(wide[index.at(position)]);
    }
    sink_.describe(columns_);
    drawing_.describe(drawn);
  }
  void start(int columns, std::int64_t rows) override {
    wide_ = columns;
    sink_.start(static_cast<int>(picks_.size()), rows);
    drawing_.start(static_cast<int>(picks_.size() + pose_picks_.size()), rows);
  }
  void write(const double* rows, std::int64_t count) override {
    const std::size_t narrow = picks_.size(), drawn = narrow + pose_picks_.size();
    narrow_.resize(static_cast<std::size_t>(count) * narrow);
    drawn_.resize(static_cast<std::size_t>(count) * drawn);
    for (std::int64_t i = 0; i < count; ++i) {
      const double* row = rows + i * wide_;
      double* to_sink = narrow_.data() + static_cast<std::size_t>(i) * narrow;
      double* to_drawing = drawn_.data() + static_cast<std::size_t>(i) * drawn;
      for (std::size_t c = 0; c < narrow; ++c) to_sink[c] = to_drawing[c] = row[picks_[c]];
      for (std::size_t c = 0; c < pose_picks_.size(); ++c) to_drawing[narrow + c] = row[pose_picks_[c]];
    }
    sink_.write(narrow_.data(), count);
    drawing_.write(drawn_.data(), count);
  }
  // The wide final row as the trajectory's.
  [[nodiscard]] std::vector<double> narrowed(const std::vector<double>& wide_row) const {
    std::vector<double> out;
    for (std::size_t c : picks_) out.push_back(wide_row[c]);
    return out;
  }

 private:
  std::vector<Column> columns_;
  std::vector<std::string> bodies_;
  std::vector<std::string> positions_;
  RowSink& sink_;
  RowSink& drawing_;
  std::vector<std::size_t> picks_, pose_picks_;
  std::int64_t wide_ = 0;
  std::vector<double> narrow_, drawn_;
};

}  // namespace

RunRecord run_scenario_drawn(const Model& scene, const Scenario& scenario, const ScenarioConfig& config, RowSink& sink,
                             RowSink& drawing, RunControl* control) {
  const Model model = scene.for_run(run_timestep(scene, scenario, config), false);
  const PreparedRun run = prepare(model, scenario, config);
  const Model with_params = with_scene_params(model, run.schedule.start.params);  // as run_scenario's
  const mjModel* m = with_params.get();
  ResolvedScenario wide = run.resolved;
  for (int id : moving_body_ids(m)) {
    if (std::find(wide.bodies.begin(), wide.bodies.end(), id) == wide.bodies.end()) wide.bodies.push_back(id);
  }
  std::vector<std::string> positions;
  for (int j = 0; j < m->njnt; ++j) {
    if (std::find(wide.joints.begin(), wide.joints.end(), j) == wide.joints.end()) wide.joints.push_back(j);
    for (std::string& column : joint_position_columns(m, j)) positions.push_back(std::move(column));
  }
  const std::vector<std::string> bodies = moving_bodies(model);
  DrawingSplit split(run.recorder->columns(), bodies, positions, sink, drawing);
  Data workspace(with_params);
  RunRecord result = run_schedule(m, workspace.get(), wide, run.schedule, config.record_every, &split, control);
  result.columns = run.recorder->columns();
  result.final_row = split.narrowed(result.final_row);
  return labelled(std::move(result), m, scenario, config);
}

}  // namespace simloop
