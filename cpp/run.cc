#include "simloop/run.hpp"
#include "mujoco_compat.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "divergence.hpp"
#include "energy_audit.hpp"
#include "mujoco_guard.hpp"
#include "run_detail.hpp"
#include "warning_counter.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"

namespace simloop {
namespace {

// "1.6 TiB": a byte count for people.
std::string human_bytes(std::uint64_t bytes) {
  static constexpr const char* kUnits[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double value = static_cast<double>(bytes);
  int unit = 0;
  while (value >= 1024.0 && unit < 6) {
    value /= 1024.0;
    ++unit;
  }
  char text[32];
  if (unit == 0) {
    std::snprintf(text, sizeof text, "%llu bytes", static_cast<unsigned long long>(bytes));
  } else {
    std::snprintf(text, sizeof text, "%.1f %s", value, kUnits[unit]);
  }
  return text;
}

// The cgroup (v2) memory limit at /sys/fs/cgroup (a container's own limit),
// or UINT64_MAX if none.
std::uint64_t cgroup_memory_max() noexcept {
  std::FILE* f = std::fopen("/sys/fs/cgroup/memory.max", "r");
  if (f == nullptr) return std::numeric_limits<std::uint64_t>::max();
  unsigned long long limit = 0;
  const bool numeric = std::fscanf(f, "%llu", &limit) == 1;  // "max" when unlimited
  std::fclose(f);
  return numeric && limit > 0 ? limit : std::numeric_limits<std::uint64_t>::max();
}

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

std::vector<Column> chapter_columns(int count) {
  static constexpr const char* kUnits[Trajectory::kNumColumns] = {
      "", "s", "", "N", "N", "N", "m", "m", "m", "", "", "", "", "m/s", "m/s", "m/s", "rad/s", "rad/s", "rad/s",
      "m", "m/s", "", "J", "J", "J", "J", "J", "J", "J"};
  std::vector<Column> columns;
  for (int c = 0; c < count && c < Trajectory::kNumColumns; ++c) {
    columns.push_back({std::string(Trajectory::kColumnNames[c]), kUnits[c], Trajectory::is_integer_column(c),
                       Trajectory::is_input_column(c)});
  }
  return columns;
}

void validate(const RunConfig& config) {
  std::ostringstream msg;
  if (!(std::isfinite(config.timestep) && config.timestep > 0.0)) {
    msg << "timestep must be a positive, finite number of seconds, got " << python_float_repr(config.timestep);
  } else if (config.num_steps() < 1) {
    msg << "steps must be at least 1, got " << config.num_steps();
  } else if (config.num_steps() > kMaxSteps) {
    msg << "steps must be at most " << kMaxSteps << ", got " << config.num_steps();
  } else if (config.record_every < 1) {
    msg << "record_every must be at least 1, got " << config.record_every;
  } else if (config.record_every > kMaxRecordEvery) {
    msg << "record_every must be at most " << kMaxRecordEvery << ", got " << config.record_every;
  } else {
    return;
  }
  throw InvalidArgument(msg.str());
}

std::uint64_t trajectory_memory_budget() noexcept {
  std::uint64_t limit = std::numeric_limits<std::uint64_t>::max();
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page_size = ::sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page_size > 0) {
    limit = static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size);
  }
  limit = std::min(limit, cgroup_memory_max());
  for (const int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    struct rlimit rl {};
    if (::getrlimit(resource, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
      limit = std::min<std::uint64_t>(limit, rl.rlim_cur);
    }
  }
  return limit / 2;
}

std::uint64_t kept_trajectory_bytes(const RunConfig& config) noexcept {
  const auto rows = static_cast<std::uint64_t>(Trajectory::rows_for(config.num_steps(), config.record_every));
  const std::uint64_t row_bytes =
      sizeof(double) * static_cast<std::uint64_t>(config.audit_energy ? Trajectory::kNumColumns
                                                                      : Trajectory::kNumBaseColumns);
  constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();
  return rows > kMax / row_bytes ? kMax : rows * row_bytes;
}

void check_kept_trajectories(const std::vector<RunConfig>& configs, std::uint64_t budget) {
  constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();
  std::uint64_t total = 0;
  std::size_t largest = 0;
  std::uint64_t largest_bytes = 0;
  for (std::size_t i = 0; i < configs.size(); ++i) {
    const std::uint64_t bytes = kept_trajectory_bytes(configs[i]);
    total = bytes > kMax - total ? kMax : total + bytes;
    if (bytes > largest_bytes) {
      largest = i;
      largest_bytes = bytes;
    }
  }
  if (total <= budget) return;
  const RunConfig& c = configs[largest];
  std::ostringstream msg;
  msg << "steps " << c.num_steps() << " with record_every " << c.record_every;
  if (configs.size() == 1) {
    msg << " would keep " << human_bytes(total) << " of trajectory in memory";
  } else {
    msg << " (run " << largest << ", the largest of " << configs.size() << " runs) and the others would keep "
        << human_bytes(total) << " of trajectories in memory";
  }
  msg << " (at most " << human_bytes(budget)
      << " allowed: half of the machine's memory or the process's limit); raise record_every, "
         "or let sim_loop stream it to a file";
  throw InvalidArgument(msg.str());
}

void detail::check_kept_rows(std::int64_t steps, std::int64_t record_every, int columns) {
  const std::uint64_t budget = trajectory_memory_budget();
  const long double bytes = static_cast<long double>(Trajectory::rows_for(steps, record_every)) * columns * sizeof(double);
  if (bytes <= static_cast<long double>(budget)) return;
  std::ostringstream msg;
  msg << "steps " << steps << " with record_every " << record_every << " would keep "
      << human_bytes(bytes >= 1.8e19L ? std::numeric_limits<std::uint64_t>::max() : static_cast<std::uint64_t>(bytes))
      << " of trajectory (" << columns << " columns) in memory (at most " << human_bytes(budget)
      << " allowed: half of the machine's memory or the process's limit); raise record_every, "
         "or let sim_loop stream it to a file";
  throw InvalidArgument(msg.str());
}

void detail::check_kept_rows(const std::vector<std::array<std::int64_t, 3>>& runs) {
  if (runs.size() == 1) return check_kept_rows(runs[0][0], runs[0][1], static_cast<int>(runs[0][2]));
  const std::uint64_t budget = trajectory_memory_budget();
  long double total = 0.0L, largest_bytes = -1.0L;
  std::size_t largest = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const long double bytes =
        static_cast<long double>(Trajectory::rows_for(runs[i][0], runs[i][1])) * runs[i][2] * sizeof(double);
    total += bytes;
    if (bytes > largest_bytes) {
      largest = i;
      largest_bytes = bytes;
    }
  }
  if (total <= static_cast<long double>(budget)) return;
  std::ostringstream msg;
  msg << "steps " << runs[largest][0] << " with record_every " << runs[largest][1] << " (run " << largest
      << ", the largest of " << runs.size() << " runs) and the others would keep "
      << human_bytes(total >= 1.8e19L ? std::numeric_limits<std::uint64_t>::max() : static_cast<std::uint64_t>(total))
      << " of trajectories in memory (at most " << human_bytes(budget)
      << " allowed: half of the machine's memory or the process's limit); raise record_every";
  throw InvalidArgument(msg.str());
}

RunResult run(const Model& model, const RunConfig& config) {
  validate(config);
  check_kept_trajectories({config});  // before allocating anything
  Data workspace(model);
  return detail::run_counted_elsewhere(model, config, workspace, nullptr, nullptr);
}

namespace {



}  // namespace

RunResult run(const Model& model, const RunConfig& config, Data& workspace, RowSink* sink,
              RunControl* control) {
  validate(config);
  if (sink == nullptr) check_kept_trajectories({config});
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
  result.shove = draw_shove(config.seed, steps, config.rng);
  result.rows = Trajectory::rows_for(steps, every);
  const Shove& shove = result.shove;
  const bool audit = config.audit_energy;
  const int columns = audit ? Trajectory::kNumColumns : Trajectory::kNumBaseColumns;
  detail::KeepRows keep(result.trajectory);
  RowSink& rows = sink ? *sink : keep;
  rows.start(columns, result.rows);
  detail::RowBlock block(columns, std::min(result.rows, RunControl::kChunkSteps / every + 2));
  detail::WarningCounter warnings;
  detail::DivergenceCheck divergence(m);
  detail::EnergyAudit energy(detail::compat::as_int(m->nv));
  double box_pos_at_push[3] = {};

  double* box_force = d->xfrc_applied + 6 * at.box_body;
  // mj_forward fills in the derived state (poses, contacts) without
  // advancing time, so row 0 is the true rest pose at t = 0.
  const auto stepping_error = [&](const MujocoError& e, std::int64_t from, std::int64_t to) {
    std::ostringstream msg;
    msg << "running the model at timestep " << python_float_repr(m->opt.timestep) << " s, in steps " << from
        << " to " << to << ": " << e.what();
    return MujocoError(msg.str());
  };
  try {
    detail::mujoco_call([&] {
      mj_resetData(m, d);
      mj_forward(m, d);
    });
  } catch (const MujocoError& e) {
    throw stepping_error(e, 0, 0);
  }
  std::int64_t until_record = 0;  // counts down to the next recorded step
  // The loop runs in chunks: each inside one guard (a MuJoCo error jumps back
  // out of it, and nothing inside owns anything that would need destroying),
  // then the chunk's rows go to the sink and the control may stop the run.
  for (std::int64_t step = 0; step < steps;) {
    const std::int64_t chunk_start = step;
    const std::int64_t chunk_end = std::min(steps, step + RunControl::kChunkSteps);
    try {
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
          divergence.after_step(d, step);
          if (audit) {
            // The row's state is the one this step started from: its energy is
            // known now, and the work before this step's is what the row holds.
            const double entering = energy.observe(d);
            if (recorded) energy.fill_row(block.last(), entering);
            energy.add_step_work(m, d, at.box_body);
          }
        }
      });
    } catch (const MujocoError& e) {
      throw stepping_error(e, chunk_start, chunk_end - 1);
    }
    block.flush_to(rows);
    if (control) control->advance(chunk_end - chunk_start);
  }
  record_row(block.next(), steps, d, at, false);
  if (audit) {
    // MuJoCo computes energy during a step; the final state has had none,
    // so a forward pass (no time advances) computes its energy.
    try {
      detail::mujoco_call([&] { mj_forward(m, d); });
    } catch (const MujocoError& e) {
      throw stepping_error(e, steps, steps);
    }
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
  Metrics& exact = result.unrounded_metrics;
  exact = metrics;
  for (int i = 0; i < 3; ++i) exact.box_final_pos[i] = box_q[i];
  exact.box_final_speed = speed;
  exact.pusher_final_x = d->qpos[at.pusher_qposadr];
  exact.lateral_drift = drift;

  result.warnings = warnings.warnings();
  if (divergence.diverged()) result.warnings.push_back(divergence.warning());
  result.sim_time = d->time;
  return result;
}

}  // namespace simloop
