// The chapter's view of its scenario: the chapter is Scenario::chapter()
// (chapter_scenario fits it to a scene) run as any scenario runs, and this
// file only turns that run into the chapter's report: its columns in its
// order, metrics.json's numbers, the energy totals, the shove drawn.
#include "simloop/run.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "chapter_detail.hpp"
#include "loop.hpp"
#include "run_detail.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"
#include "simloop/recorder.hpp"

namespace simloop {
namespace {

constexpr double kNone = std::numeric_limits<double>::quiet_NaN();

// Where the box was as the shove's window began (its drift is measured from
// there), read whether or not the shove is applied: a copy, as the chapter
// takes it, of xpos, which the next step overwrites.
class ShoveOrigin final : public detail::StepObserver {
 public:
  ShoveOrigin(int box_body, std::int64_t start_step) : box_body_(box_body), start_step_(start_step) {}
  void before_step(std::int64_t step, const mjModel* /*m*/, const mjData* d) noexcept override {
    if (step == start_step_) y_ = d->xpos[3 * box_body_ + 1];
  }
  [[nodiscard]] double y() const noexcept { return y_; }

 private:
  int box_body_;
  std::int64_t start_step_;
  double y_ = 0.0;  // the drift is sideways: y only
};

// The chapter's rows made from its scenario's as they come: the chapter's
// columns in its order. ctrl is the value written (the schedule's, before
// ctrlrange clamping); shove_x.. the force on the box, zeros in a run
// without the shove; the final row's inputs NaN, as every run's.
class ChapterRows final : public RowSink {
 public:
  // motor: actuator 0's ctrl column; pusher_joint: its joint's columns' stem.
  ChapterRows(RowSink& to, int width, std::string motor, std::string pusher_joint, double ctrl)
      : to_(to), width_(width), motor_(std::move(motor)), pusher_joint_(std::move(pusher_joint)), ctrl_(ctrl) {}

  void describe(const std::vector<Column>& columns) override {
    const auto at = [&](const std::string& name) {
      const auto it = std::find_if(columns.begin(), columns.end(), [&](const Column& c) { return c.name == name; });
      return it == columns.end() ? -1 : static_cast<int>(it - columns.begin());
    };
    std::vector<int> from(static_cast<std::size_t>(width_), -1);
    for (int c = 0; c < width_; ++c) from[static_cast<std::size_t>(c)] = at(std::string(ChapterColumns::kNames[c]));
    for (int i = 0; i < 3; ++i) from[ChapterColumns::kShoveX + i] = at(std::string("box_f") + "xyz"[i]);
    from[ChapterColumns::kPusherX] = at(pusher_joint_ + "_pos");
    from[ChapterColumns::kPusherVx] = at(pusher_joint_ + "_vel");
    copies_.clear();
    absent_.clear();
    for (int c = 0; c < width_; ++c) {
      if (c == ChapterColumns::kCtrl) continue;
      if (from[static_cast<std::size_t>(c)] >= 0) {
        copies_.push_back({c, from[static_cast<std::size_t>(c)]});
      } else {
        absent_.push_back(c);  // a shove column of a run without the shove
      }
    }
    motor_column_ = at(motor_);
    source_width_ = static_cast<int>(columns.size());
    to_.describe(chapter_columns(width_));
  }
  void start(int /*columns*/, std::int64_t rows) override { to_.start(width_, rows); }
  void write(const double* rows, std::int64_t count) override {
    buffer_.resize(static_cast<std::size_t>(count * width_));
    for (std::int64_t r = 0; r < count; ++r) view(rows + r * source_width_, buffer_.data() + r * width_);
    to_.write(buffer_.data(), count);
  }

  // One row in the chapter's columns.
  void view(const double* row, double* out) const noexcept {
    for (const auto& [to, from] : copies_) out[to] = row[from];
    const bool inputs = !std::isnan(row[motor_column_]);  // the final row has none
    for (const int c : absent_) out[c] = inputs ? 0.0 : kNone;
    out[ChapterColumns::kCtrl] = inputs ? ctrl_ : kNone;
  }

 private:
  RowSink& to_;
  int width_;
  std::string motor_, pusher_joint_;
  double ctrl_;
  std::vector<std::pair<int, int>> copies_;  // (chapter column, scenario column)
  std::vector<int> absent_;
  int motor_column_ = 0;
  int source_width_ = 0;
  std::vector<double> buffer_;
};

// The chapter's motor, pusher and the value the chapter writes to ctrl.
struct ChapterParts {
  ChapterLayout at;
  Scenario scenario;
  std::string motor, pusher_joint;
  double ctrl = 0.0;
};

ChapterParts chapter_parts(const Model& model) {
  ChapterParts parts;
  parts.at = chapter_layout(model);
  parts.scenario = chapter_scenario(model);
  parts.motor = object_name(model.get(), mjOBJ_ACTUATOR, 0) + "_ctrl";
  parts.pusher_joint = object_name(model.get(), mjOBJ_JOINT, parts.at.pusher_joint);
  parts.ctrl = parts.scenario.controls.front().schedule.front().second;
  return parts;
}

int chapter_width(const RunConfig& config) {
  return config.audit_energy ? ChapterColumns::kNumColumns : ChapterColumns::kNumBaseColumns;
}

// One chapter run's parts: the shove drawn for it, its rows' view and its
// observer.
struct ChapterRun {
  ChapterRun(const ChapterParts& parts, const RunConfig& asked, RowSink* sink)
      : config(asked),
        shove(draw_shove(asked.seed, asked.num_steps(), asked.rng)),
        keep(trajectory),
        rows(sink ? *sink : keep, chapter_width(asked), parts.motor, parts.pusher_joint, parts.ctrl),
        origin(parts.at.box_body, shove.start_step) {}
  const RunConfig& config;  // the caller's, which outlives the run
  Shove shove;
  Trajectory trajectory;  // the rows, unless they go to a sink
  detail::KeepRows keep;
  ChapterRows rows;
  ShoveOrigin origin;
};

// The chapter's report on a run of its scenario.
RunResult chapter_result(RunRecord record, ChapterRun& run) {
  const RunConfig& config = run.config;
  RunResult result;
  std::vector<double> final_row(static_cast<std::size_t>(chapter_width(config)));
  run.rows.view(record.final_row.data(), final_row.data());
  static_cast<RunRecord&>(result) = std::move(record);
  result.columns = chapter_columns(chapter_width(config));
  result.final_row = std::move(final_row);
  result.trajectory = std::move(run.trajectory);
  result.config = config;
  result.shove = run.shove;

  // Inspect, as the chapter does: the box's free joint's position and linear
  // velocity, and the pusher's joint, in the final state.
  const double* box_q = result.final_row.data() + ChapterColumns::kBoxX;
  const double* box_v = result.final_row.data() + ChapterColumns::kBoxVx;
  const double pusher_x = result.final_row[ChapterColumns::kPusherX];
  const double speed = std::sqrt(box_v[0] * box_v[0] + box_v[1] * box_v[1] + box_v[2] * box_v[2]);
  const double drift = std::fabs(box_q[1] - run.origin.y());
  Metrics& metrics = result.metrics;
  metrics.steps = config.num_steps();
  metrics.seed = config.seed;
  metrics.perturb = config.perturb;
  for (int i = 0; i < 3; ++i) metrics.box_final_pos[i] = round6(box_q[i]);
  metrics.box_final_speed = round6(speed);
  metrics.pusher_final_x = round6(pusher_x);
  metrics.lateral_drift = round6(drift);
  metrics.shove_moved_box = drift > 0.01;
  Metrics& exact = result.unrounded_metrics;
  exact = metrics;
  for (int i = 0; i < 3; ++i) exact.box_final_pos[i] = box_q[i];
  exact.box_final_speed = speed;
  exact.pusher_final_x = pusher_x;
  exact.lateral_drift = drift;
  return result;
}

}  // namespace

std::string detail::pusher_joint_name(const Model& model) {
  return object_name(model.get(), mjOBJ_JOINT, chapter_layout(model).pusher_joint);
}

std::vector<Column> chapter_columns(int count) {
  static constexpr const char* kUnits[ChapterColumns::kNumColumns] = {
      "",    "s",     "",      "N",     "N", "N",   "m", "m", "m", "",  "",  "",  "",  "m/s", "m/s",
      "m/s", "rad/s", "rad/s", "rad/s", "m", "m/s", "",  "J", "J", "J", "J", "J", "J", "J"};
  std::vector<Column> columns;
  for (int c = 0; c < count && c < ChapterColumns::kNumColumns; ++c) {
    columns.push_back({std::string(ChapterColumns::kNames[c]), kUnits[c],
                       c == ChapterColumns::kStep || c == ChapterColumns::kNcon,
                       c >= ChapterColumns::kCtrl && c <= ChapterColumns::kShoveZ, ""});
  }
  return columns;
}

void validate(const RunConfig& config) {
  check_positive_seconds("timestep", config.timestep);
  check_count("steps", config.num_steps(), kMaxSteps);
  check_count("record_every", config.record_every, kMaxRecordEvery);
}

KeptRows kept_rows(const RunConfig& config) noexcept {
  return {config.num_steps(), config.record_every, chapter_width(config)};
}

Scenario chapter_scenario(const Model& model) {
  const ChapterLayout at = chapter_layout(model);
  const mjModel* m = model.get();
  Scenario chapter = Scenario::chapter();
  // Actuator 0 and its joint by index: another scene's motor and pusher have
  // other names (or none).
  chapter.controls.front().actuator = "0";
  const char* joint = mj_id2name(m, mjOBJ_JOINT, at.pusher_joint);
  chapter.record.joints = {joint && *joint ? std::string(joint) : std::to_string(at.pusher_joint)};
  return chapter;
}

ScenarioConfig scenario_config(const RunConfig& config) {
  ScenarioConfig c;
  c.seed = config.seed;
  c.rng = config.rng;
  c.timestep = config.timestep;
  c.steps = config.num_steps();
  c.perturb = config.perturb;
  c.record_every = config.record_every;
  c.audit_energy = config.audit_energy;
  return c;
}

RunResult run(const Model& model, const RunConfig& config) {
  validate(config);
  check_kept_rows({kept_rows(config)});  // before allocating anything
  Data workspace(model);
  return detail::run_counted_elsewhere(model, config, workspace, nullptr, nullptr);
}

RunResult run(const Model& model, const RunConfig& config, Data& workspace, RowSink* sink, RunControl* control) {
  validate(config);
  if (sink == nullptr) check_kept_rows({kept_rows(config)});
  if (control) control->add_total(config.num_steps());
  return detail::run_counted_elsewhere(model, config, workspace, sink, control);
}

RunResult detail::run_counted_elsewhere(const Model& model, const RunConfig& config, Data& workspace, RowSink* sink,
                                        RunControl* control) {
  validate(config);
  const ChapterParts parts = chapter_parts(model);
  ChapterRun run(parts, config, sink);
  RunRecord record = run_scenario_watched(model, parts.scenario, scenario_config(config), workspace, &run.rows, control,
                                          {&run.origin}, false);
  return chapter_result(std::move(record), run);
}

std::vector<RunResult> detail::run_chapter_batch(const Model& model, const std::vector<RunConfig>& configs,
                                                 const std::vector<RowSink*>& sinks, int threads, RunControl* control) {
  check_threads(threads);
  for (std::size_t i = 0; i < configs.size(); ++i) check_run(i, [&] { validate(configs[i]); });
  if (sinks.empty()) {
    std::vector<KeptRows> kept;
    for (const RunConfig& config : configs) kept.push_back(kept_rows(config));
    check_kept_rows(kept);
  } else if (sinks.size() != configs.size() || std::find(sinks.begin(), sinks.end(), nullptr) != sinks.end()) {
    throw InvalidArgument("sinks: one RowSink per config, none null, got " + std::to_string(sinks.size()) + " for " +
                          std::to_string(configs.size()) + " configs");
  }
  const ChapterParts parts = chapter_parts(model);
  std::vector<std::unique_ptr<ChapterRun>> runs;
  std::vector<ScenarioConfig> scenario_configs;
  std::vector<RowSink*> rows;
  std::vector<std::vector<StepObserver*>> watching;
  for (std::size_t i = 0; i < configs.size(); ++i) {
    runs.push_back(std::make_unique<ChapterRun>(parts, configs[i], sinks.empty() ? nullptr : sinks[i]));
    scenario_configs.push_back(scenario_config(configs[i]));
    rows.push_back(&runs.back()->rows);
    watching.push_back({&runs.back()->origin});
  }
  std::vector<RunRecord> records =
      run_scenario_batch_watched(model, parts.scenario, scenario_configs, rows, threads, control, {}, watching);
  std::vector<RunResult> results;
  results.reserve(records.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    results.push_back(chapter_result(std::move(records[i]), *runs[i]));
  }
  return results;
}

}  // namespace simloop
