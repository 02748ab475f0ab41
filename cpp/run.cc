#include "simloop/run.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "chapter_detail.hpp"
#include "energy_audit.hpp"
#include "loop.hpp"
#include "mujoco_compat.hpp"
#include "run_detail.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/recorder.hpp"
#include "simloop/scenario.hpp"

namespace simloop {
namespace {

// The chapter's row: the state entering the step and the inputs just written
// (NaN in the final row, which has no step after it), all read before the
// step as the chapter reads them (ncon: the contacts the last step found).
class ChapterRecorder final : public RowRecorder {
 public:
  ChapterRecorder(const ChapterLayout& at, int columns) : at_(at), columns_(chapter_columns(columns)) {}
  [[nodiscard]] const std::vector<Column>& columns() const noexcept override { return columns_; }
  void before_step(double* row, std::int64_t step, const mjModel* /*m*/, const mjData* d, bool inputs,
                   int ncon) const noexcept override {
    const auto put = [row](int column, double value) { row[column] = value; };
    const double* box_q = d->qpos + at_.box_qposadr;
    const double* box_v = d->qvel + at_.box_dofadr;
    const double* shove = d->xfrc_applied + 6 * at_.box_body;
    constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
    put(ChapterColumns::kStep, static_cast<double>(step));
    put(ChapterColumns::kTime, d->time);
    put(ChapterColumns::kCtrl, inputs ? d->ctrl[0] : kNone);
    for (int i = 0; i < 3; ++i) put(ChapterColumns::kShoveX + i, inputs ? shove[i] : kNone);
    for (int i = 0; i < 7; ++i) put(ChapterColumns::kBoxX + i, box_q[i]);
    for (int i = 0; i < 6; ++i) put(ChapterColumns::kBoxVx + i, box_v[i]);
    put(ChapterColumns::kPusherX, d->qpos[at_.pusher_qposadr]);
    put(ChapterColumns::kPusherVx, d->qvel[at_.pusher_dofadr]);
    put(ChapterColumns::kNcon, ncon);
  }
  void after_step(double* /*row*/, const mjModel* /*m*/, const mjData* /*d*/) const noexcept override {}

 private:
  ChapterLayout at_;
  std::vector<Column> columns_;
};

// The chapter's inputs, drawn as Scenario::chapter()'s: full throttle on
// actuator 0 from step 0, and the shove on the box for its window (if the
// run is perturbed). Actuator 0 by index, and nothing named to record:
// another scene's motor and pusher have other names.
Schedule chapter_schedule(const mjModel* m, const RunConfig& config) {
  Scenario chapter = Scenario::chapter();
  chapter.controls.front().actuator = "0";
  chapter.record = RecordSpec{};
  chapter.length = When::steps(config.num_steps());
  if (!config.perturb) chapter.disturbances.clear();
  const std::unique_ptr<Draws> draws = make_draws(config.seed, config.rng);
  return build_schedule(resolve(chapter, m), chapter, m->opt.timestep, *draws);
}

// What the chapter watches besides the rows: where the box was when the
// shove began (its drift is measured from there), and with the energy
// audit, the energy of each row's state and the work done up to it.
class ChapterWatch final : public detail::StepObserver {
 public:
  ChapterWatch(const mjModel* m, const ChapterLayout& at, std::int64_t shove_start, bool audit)
      : box_body_(at.box_body), shove_start_(shove_start), audit_(audit), energy_(detail::compat::as_int(m->nv)) {}

  void before_step(std::int64_t step, const mjModel* /*m*/, const mjData* d) noexcept override {
    // A copy, as the chapter takes: xpos is overwritten by the next step.
    if (step == shove_start_) box_y_at_shove_ = d->xpos[3 * box_body_ + 1];
    if (audit_) energy_.before_step(d);
  }
  void after_step(std::int64_t /*step*/, const mjModel* m, mjData* d, double* row) noexcept override {
    if (!audit_) return;
    // The row's state is the one this step started from: its energy is known
    // now, and the work before this step's is what the row holds.
    const double entering = energy_.observe(d);
    if (row) energy_.fill_row(row, entering);
    energy_.add_step_work(m, d, box_body_);
  }
  void at_end(const mjModel* /*m*/, const mjData* d, double* row) noexcept override {
    if (!audit_) return;
    final_energy_ = d->energy[0] + d->energy[1];  // from the loop's final mj_forward
    energy_.fill_row(row, final_energy_);
  }

  [[nodiscard]] double box_y_at_shove() const noexcept { return box_y_at_shove_; }
  [[nodiscard]] EnergyTotals energy() const noexcept { return audit_ ? energy_.totals(final_energy_) : EnergyTotals{}; }

 private:
  int box_body_;
  std::int64_t shove_start_;
  bool audit_;
  detail::EnergyAudit energy_;
  double box_y_at_shove_ = 0.0;  // the drift is sideways: y only
  double final_energy_ = 0.0;
};

}  // namespace

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
  return {config.num_steps(), config.record_every,
          config.audit_energy ? ChapterColumns::kNumColumns : ChapterColumns::kNumBaseColumns};
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

RunResult detail::run_counted_elsewhere(const Model& model_in, const RunConfig& config, Data& workspace, RowSink* sink,
                                        RunControl* control) {
  validate(config);
  const Model model = model_in.for_run(config.timestep, config.audit_energy);
  if (!workspace.fits(model)) {
    throw InvalidArgument("workspace Data was made for a model of another size");
  }
  const mjModel* m = model.get();
  const bool d_is_reset = workspace.fresh_for(model);  // before get(), which ends that
  mjData* d = workspace.get();
  const ChapterLayout at = chapter_layout(model);
  const std::int64_t steps = config.num_steps();

  RunResult result;
  result.config = config;
  result.shove = draw_shove(config.seed, steps, config.rng);
  result.schedule = chapter_schedule(m, config);
  const ChapterRecorder recorder(at,
                                 config.audit_energy ? ChapterColumns::kNumColumns : ChapterColumns::kNumBaseColumns);
  ChapterWatch watch(m, at, result.shove.start_step, config.audit_energy);
  detail::KeepRows keep(result.trajectory);
  detail::LoopResult loop = detail::run_loop(m, d, result.schedule, recorder, config.record_every, sink ? *sink : keep,
                                             control, RunInputs{}, {&watch}, d_is_reset);
  // The record any run leaves, as the chapter's scenario would label it.
  result.name = std::string(kChapterScenarioName);
  result.seed = config.seed;
  result.rng = std::string(rng_name(config.rng));
  result.perturb = config.perturb;
  if (config.perturb) result.disturbed_bodies = {mj_id2name(m, mjOBJ_BODY, at.box_body)};
  result.columns = recorder.columns();
  result.final_row = std::move(loop.final_row);
  result.final_state = std::move(loop.final_state);
  result.timestep = loop.timestep;
  result.rows = loop.rows;
  result.warnings = std::move(loop.warnings);
  result.sim_time = loop.sim_time;
  result.energy = watch.energy();

  // Inspect, as the chapter does: the box's free joint owns qpos[adr..adr+3)
  // (position) and qvel[adr..adr+3) (linear velocity).
  const double* box_q = d->qpos + at.box_qposadr;
  const double* box_v = d->qvel + at.box_dofadr;
  const double speed = std::sqrt(box_v[0] * box_v[0] + box_v[1] * box_v[1] + box_v[2] * box_v[2]);
  const double drift = std::fabs(box_q[1] - watch.box_y_at_shove());
  Metrics& metrics = result.metrics;
  metrics.steps = steps;
  metrics.seed = config.seed;
  metrics.perturb = config.perturb;
  for (int i = 0; i < 3; ++i) metrics.box_final_pos[i] = round6(box_q[i]);
  metrics.box_final_speed = round6(speed);
  metrics.pusher_final_x = round6(d->qpos[at.pusher_qposadr]);
  metrics.lateral_drift = round6(drift);
  metrics.shove_moved_box = drift > 0.01;
  Metrics& exact = result.unrounded_metrics;
  exact = metrics;
  for (int i = 0; i < 3; ++i) exact.box_final_pos[i] = box_q[i];
  exact.box_final_speed = speed;
  exact.pusher_final_x = d->qpos[at.pusher_qposadr];
  exact.lateral_drift = drift;
  return result;
}

}  // namespace simloop
