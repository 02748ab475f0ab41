#include "simloop/run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "energy_audit.hpp"
#include "mujoco_guard.hpp"
#include "run_detail.hpp"
#include "warning_counter.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"

namespace simloop {
namespace {

// Trajectories beyond this are refused up front rather than left to the
// allocator (4 GiB: 24 million rows of the 22 columns).
constexpr std::int64_t kMaxTrajectoryValues = std::int64_t{1} << 29;

// Writes one trajectory row: the state now, and the inputs just written
// (or NaN for the final row, which has no step after it).
void record_row(double* values, std::int64_t step, const mjData* d, const SceneLayout& at, bool with_inputs) {
  const auto put = [values](int column, double value) { values[column] = value; };
  const double* box_q = d->qpos + at.box_qposadr;
  const double* box_v = d->qvel + at.box_dofadr;
  const double* shove = d->xfrc_applied + 6 * at.box_body;
  constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  put(Trajectory::kStep, static_cast<double>(step));
  put(Trajectory::kTime, d->time);
  put(Trajectory::kCtrl, with_inputs ? d->ctrl[0] : kNone);
  for (int i = 0; i < 3; ++i) put(Trajectory::kShoveX + i, with_inputs ? shove[i] : kNone);
  for (int i = 0; i < 7; ++i) put(Trajectory::kBoxX + i, box_q[i]);
  for (int i = 0; i < 6; ++i) put(Trajectory::kBoxVx + i, box_v[i]);
  put(Trajectory::kPusherX, d->qpos[at.pusher_qposadr]);
  put(Trajectory::kPusherVx, d->qvel[at.pusher_dofadr]);
  put(Trajectory::kNcon, d->ncon);
}

}  // namespace

void validate(const RunConfig& config) {
  std::ostringstream msg;
  if (!(std::isfinite(config.timestep) && config.timestep > 0.0)) {
    msg << "timestep must be a positive, finite number of seconds, got " << python_float_repr(config.timestep);
  } else if (config.num_steps() < 1) {
    msg << "steps must be at least 1, got " << config.num_steps();
  } else if (config.record_every < 1) {
    msg << "record_every must be at least 1, got " << config.record_every;
  } else if (Trajectory::rows_for(config.num_steps(), config.record_every) >
             kMaxTrajectoryValues / Trajectory::kNumColumns) {
    msg << "steps " << config.num_steps() << " with record_every " << config.record_every
        << " would record more than " << kMaxTrajectoryValues / Trajectory::kNumColumns
        << " trajectory rows; raise record_every";
  } else {
    return;
  }
  throw InvalidArgument(msg.str());
}

RunResult run(const Model& model, const RunConfig& config) {
  validate(config);
  Data workspace(model);
  return run(model, config, workspace);
}

namespace {


// The rows recorded during one chunk of steps, handed to the sink after it.
class RowBlock {
 public:
  RowBlock(int columns, std::int64_t capacity)
      : columns_(columns), values_(static_cast<size_t>(capacity) * static_cast<size_t>(columns)) {}
  [[nodiscard]] double* next() noexcept { return values_.data() + static_cast<size_t>(count_++) * columns_; }
  [[nodiscard]] double* last() noexcept { return values_.data() + static_cast<size_t>(count_ - 1) * columns_; }
  void flush_to(RowSink& sink) {
    if (count_ > 0) sink.write(values_.data(), count_);
    count_ = 0;
  }

 private:
  int columns_;
  std::int64_t count_ = 0;
  std::vector<double> values_;
};

}  // namespace

RunResult run(const Model& model, const RunConfig& config, Data& workspace, RowSink* sink,
              RunControl* control) {
  if (control) control->add_total(config.num_steps());
  return detail::run_counted_elsewhere(model, config, workspace, sink, control);
}

RunResult detail::run_counted_elsewhere(const Model& model_in, const RunConfig& config, Data& workspace,
                                        RowSink* sink, RunControl* control) {
  validate(config);
  const Model model = model_in.for_run(config.timestep, config.audit_energy);
  if (!workspace.fits(model)) {
    throw InvalidArgument("workspace Data was made for a model of another size");
  }
  const mjModel* m = model.get();
  mjData* d = workspace.get();
  const SceneLayout& at = model.layout();
  const std::int64_t steps = config.num_steps();
  const std::int64_t every = config.record_every;

  RunResult result;
  result.config = config;
  result.timestep = m->opt.timestep;
  result.shove = draw_shove(config.seed, steps);
  result.rows = Trajectory::rows_for(steps, every);
  const Shove& shove = result.shove;
  const bool audit = config.audit_energy;
  const int columns = audit ? Trajectory::kNumColumns : Trajectory::kNumBaseColumns;
  detail::KeepRows keep(result.trajectory);
  RowSink& rows = sink ? *sink : keep;
  rows.start(columns, result.rows);
  RowBlock block(columns, std::min(result.rows, RunControl::kChunkSteps / every + 2));
  detail::WarningCounter warnings;
  detail::EnergyAudit energy(m->nv);
  double box_pos_at_push[3] = {};

  double* box_force = d->xfrc_applied + 6 * at.box_body;
  // mj_forward fills in the derived state (poses, contacts) without
  // advancing time, so row 0 is the true rest pose at t = 0.
  detail::mujoco_call([&] {
    mj_resetData(m, d);
    mj_forward(m, d);
  });
  std::int64_t until_record = 0;  // counts down to the next recorded step
  // The loop runs in chunks: each inside one guard (a MuJoCo error jumps back
  // out of it, and nothing inside owns anything that would need destroying),
  // then the chunk's rows go to the sink and the control may stop the run.
  for (std::int64_t step = 0; step < steps;) {
    const std::int64_t chunk_start = step;
    const std::int64_t chunk_end = std::min(steps, step + RunControl::kChunkSteps);
    detail::mujoco_call([&] {
      for (; step < chunk_end; ++step) {
        const bool in_shove = config.perturb && shove.acts_at(step);
        if (step == shove.start_step) {
          // A copy, as the chapter takes: xpos is overwritten by the next step.
          for (int i = 0; i < 3; ++i) box_pos_at_push[i] = d->xpos[3 * at.box_body + i];
        }
        // The rhythm: write intent, write interference, step.
        d->ctrl[0] = 1.0;  // full throttle on the slide motor
        box_force[0] = 0.0;
        box_force[1] = in_shove ? shove.force_y() : 0.0;  // write 0 explicitly: xfrc_applied persists
        box_force[2] = 0.0;
        const bool recorded = until_record-- == 0;
        if (recorded) {
          record_row(block.next(), step, d, at, true);
          until_record = every - 1;
        }
        if (audit) energy.before_step(d);
        mj_step(m, d);
        warnings.after_step(d, step);
        if (audit) {
          // The row's state is the one this step started from: its energy is
          // known now, and the work before this step's is what the row holds.
          const double entering = energy.observe(d);
          if (recorded) energy.fill_row(block.last(), entering);
          energy.add_step_work(m, d, at.box_body);
        }
      }
    });
    block.flush_to(rows);
    if (control) control->advance(chunk_end - chunk_start);
  }
  record_row(block.next(), steps, d, at, false);
  if (audit) {
    // MuJoCo computes energy during a step; the final state has had none,
    // so a forward pass (no time advances) computes its energy.
    detail::mujoco_call([&] { mj_forward(m, d); });
    const double final_energy = d->energy[0] + d->energy[1];
    energy.fill_row(block.last(), final_energy);
    result.energy = energy.totals(final_energy);
  }
  block.flush_to(rows);

  // Inspect, as the chapter does: the box's free joint owns qpos[adr..adr+3)
  // (position) and qvel[adr..adr+3) (linear velocity).
  const double* box_q = d->qpos + at.box_qposadr;
  const double* box_v = d->qvel + at.box_dofadr;
  const double speed = std::sqrt(box_v[0] * box_v[0] + box_v[1] * box_v[1] + box_v[2] * box_v[2]);
  const double drift = std::fabs(box_q[1] - box_pos_at_push[1]);
  Metrics& metrics = result.metrics;
  metrics.steps = steps;
  metrics.seed = config.seed;
  metrics.perturb = config.perturb;
  for (int i = 0; i < 3; ++i) metrics.box_final_pos[i] = round6(box_q[i]);
  metrics.box_final_speed = round6(speed);
  metrics.pusher_final_x = round6(d->qpos[at.pusher_qposadr]);
  metrics.lateral_drift = round6(drift);
  metrics.shove_moved_box = drift > 0.01;

  result.warnings = warnings.warnings();
  result.sim_time = d->time;
  return result;
}

}  // namespace simloop
