#include "simloop/episode.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "loop.hpp"
#include "mujoco_compat.hpp"
#include "mujoco_guard.hpp"
#include "run_detail.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/rows.hpp"
#include "simloop/scene_params.hpp"
#include "simloop/shove.hpp"
#include "simloop/state.hpp"
#include "worker_pool.hpp"

namespace simloop {

namespace {

// One episode: its own Data, the schedule drawn at its reset, where it is.
struct Episode {
  explicit Episode(const Model& shared) : model(shared), data(shared), health(shared.get()) {}
  Model model;  // the shared one, or a copy with this episode's scene parameters (the same sizes)
  Data data;
  Schedule schedule;
  std::optional<ScheduledInputs> inputs;  // empty until the first reset
  std::int64_t step = 0;
  detail::StepHealth health;
  std::optional<detail::DecisionStep> decision;  // from the first reset
};

// `count` episodes' data, each `bytes`, fit the memory budget a run's
// trajectories get: a million envs are refused at once, not by the kernel.
void check_episodes_memory(std::size_t count, std::size_t bytes) {
  const std::uint64_t budget = trajectory_memory_budget();
  if (bytes > 0 && count > budget / bytes) {
    throw InvalidArgument(std::to_string(count) + " episodes need " + std::to_string(count) + " x " +
                          std::to_string(bytes >> 10) + " KiB of MuJoCo data, more than the " +
                          std::to_string(budget >> 20) +
                          " MiB allowed (half of the machine's memory or the process's limit); run fewer");
  }
}

}  // namespace

struct Episodes::Impl {
  Model model;
  Scenario scenario;  // as configured (length, disturbances)
  ScenarioConfig config;
  ResolvedScenario resolved;
  std::optional<Recorder> recorder;
  std::int64_t length = 0;  // an episode's physics steps
  std::vector<Episode> episodes;
  std::unique_ptr<detail::WorkerPool> workers = std::make_unique<detail::WorkerPool>();  // kept from step to step

  // The row for the state entering the episode's next step: the inputs
  // scheduled for it written, then what MuJoCo derives from the state.
  void observe(Episode& e, double* observation) const {
    const mjModel* m = e.model.get();
    mjData* d = e.data.get();
    detail::mujoco_call([&] {
      if (e.step < e.schedule.steps) e.inputs->write(e.step, d);
      e.decision->observe(m, d);
    });
    recorder->before_step(observation, e.step, m, d, true, e.decision->entering_ncon(d));
    recorder->after_step(observation, m, d);
  }

  [[nodiscard]] bool terminated(const Episode& e) const noexcept { return e.health.broken(); }
};

Episodes::Episodes(const Model& scene, const Scenario& scenario, const ScenarioConfig& config, std::size_t count)
    : impl_(std::make_unique<Impl>(Impl{scene.for_run(run_timestep(scene, scenario, config), false),
                                        detail::configured_scenario(scenario, config),
                                        config,
                                        {},
                                        std::nullopt,
                                        0,
                                        {}})) {
  Impl& s = *impl_;
  s.resolved = resolve(s.scenario, s.model.get());
  // The columns depend on which bodies are disturbed, not on the draws.
  const std::unique_ptr<Draws> draws = make_draws(0, config.rng);
  const Schedule schedule = build_schedule(s.resolved, s.scenario, s.model.timestep(), *draws);
  detail::check_schedule_run(schedule.steps, 1);
  s.recorder.emplace(s.model.get(), s.resolved, schedule);
  s.length = schedule.steps;
  s.episodes.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    s.episodes.emplace_back(s.model);
    if (i == 0) check_episodes_memory(count, detail::compat::data_bytes(s.episodes.front().data.get()));
  }
}

Episodes::~Episodes() = default;

std::size_t Episodes::count() const noexcept { return impl_->episodes.size(); }
int Episodes::nu() const noexcept { return detail::compat::as_int(impl_->model.get()->nu); }
int Episodes::width() const noexcept { return impl_->recorder->width(); }
const std::vector<Column>& Episodes::columns() const noexcept { return impl_->recorder->columns(); }
const Model& Episodes::model() const noexcept { return impl_->model; }

std::int64_t Episodes::steps() const noexcept { return impl_->length; }

namespace {
void check_index(std::size_t i, std::size_t count) {
  if (i >= count) {
    throw InvalidArgument("episode " + std::to_string(i) + " does not exist: there are " + std::to_string(count));
  }
}
}  // namespace

void Episodes::reset(std::size_t i, std::uint64_t seed, double* observation, const ResetSpec* reset) {
  Impl& s = *impl_;
  check_index(i, s.episodes.size());
  Episode& e = s.episodes[i];
  Scenario scenario_for_reset;
  const Scenario* spec = &s.scenario;
  if (reset != nullptr) {  // this episode's start instead of the scenario's
    check_reset(s.resolved, *reset, s.model.get());
    scenario_for_reset = s.scenario;
    scenario_for_reset.reset = *reset;
    spec = &scenario_for_reset;
  }
  const std::unique_ptr<Draws> draws = make_draws(seed, s.config.rng);
  Schedule schedule = build_schedule(s.resolved, *spec, s.model.timestep(), *draws);
  Model model = with_scene_params(s.model, schedule.start.params);
  e.schedule = std::move(schedule);
  e.model = std::move(model);
  e.inputs.emplace(e.schedule, false);  // ctrl is the actions'
  e.step = 0;
  const mjModel* m = e.model.get();
  e.health = detail::StepHealth(m);
  e.decision.emplace(m, *s.recorder);
  mjData* d = e.data.get();
  detail::guarded_steps(m, 0, 0, [&] {
    mj_resetData(m, d);
    detail::set_start(m, d, e.schedule.start);
    mj_forward(m, d);  // as run_loop starts
  });
  s.observe(e, observation);
}

const Model& Episodes::model(std::size_t i) const {
  check_index(i, impl_->episodes.size());
  return impl_->episodes[i].model;
}

const mjData* Episodes::data(std::size_t i) const {
  check_index(i, impl_->episodes.size());
  return impl_->episodes[i].data.get();
}

void Episodes::step(const double* actions, std::size_t action_count, std::int64_t every, const std::uint8_t* active,
                    std::size_t active_count, double* observations, std::uint8_t* terminated, std::uint8_t* truncated,
                    int threads, RunControl* control) {
  Impl& s = *impl_;
  const std::size_t count = s.episodes.size();
  const int nu = detail::compat::as_int(s.model.get()->nu);
  if (action_count != count * static_cast<std::size_t>(nu)) {
    throw InvalidArgument("actions must hold " + std::to_string(count) + " x " + std::to_string(nu) + " values, got " +
                          std::to_string(action_count));
  }
  if (active && active_count != count) throw InvalidArgument("active must hold " + std::to_string(count) + " flags");
  if (every < 1 || every > kMaxSteps) {
    throw InvalidArgument("control_every must be from 1 to " + std::to_string(kMaxSteps) + ", got " +
                          std::to_string(every));
  }
  const int width = s.recorder->width();
  std::vector<std::int64_t> steps(count, 0);  // each job's steps, for progress
  for (std::size_t i = 0; i < count; ++i) {
    if (active && !active[i]) continue;
    const Episode& e = s.episodes[i];
    const auto refuse = [i](const std::string& why) { throw InvalidArgument("episode " + std::to_string(i) + why); };
    if (!e.inputs) refuse(" has not started: reset it first");
    if (s.terminated(e) || e.step >= e.schedule.steps) {
      refuse(" has ended (at step " + std::to_string(e.step) + "): reset it first");
    }
    for (int a = 0; a < nu; ++a) {
      const double value = actions[i * static_cast<std::size_t>(nu) + static_cast<std::size_t>(a)];
      if (!std::isfinite(value)) {
        throw InvalidArgument((count == 1 ? std::string() : "episode " + std::to_string(i) + ": ") + "action " +
                              std::to_string(a) + " is not finite, got " + python_float_repr(value));
      }
    }
    steps[i] = std::min(every, e.schedule.steps - e.step);
  }
  // Each episode has its own Data: the pool's per-worker Data (about 1 ms to
  // make for PushT, longer than a decision's steps) is not wanted here; its
  // threads are kept from call to call.
  const auto job = [&](std::size_t i, int, RunControl& ctl) {
    if (steps[i] == 0) return;
    Episode& e = s.episodes[i];
    const mjModel* m = e.model.get();
    mjData* d = e.data.get();
    std::copy(actions + i * static_cast<std::size_t>(nu), actions + (i + 1) * static_cast<std::size_t>(nu), d->ctrl);
    const std::int64_t end = e.step + steps[i];
    while (e.step < end && !s.terminated(e)) {
      const std::int64_t chunk_start = e.step;
      const std::int64_t chunk_end = std::min(end, e.step + RunControl::kChunkSteps);
      detail::guarded_steps(m, chunk_start, chunk_end - 1, [&] {
        for (; e.step < chunk_end; ++e.step) {
          e.inputs->write(e.step, d);
          e.decision->step(m, d);  // mj_step (its second half after the observation)
          e.health.after_step(d, e.step);
          if (s.terminated(e)) {
            ++e.step;
            break;
          }
        }
      });
      ctl.advance(e.step - chunk_start);
    }
    s.observe(e, observations + i * static_cast<std::size_t>(width));
    terminated[i] = s.terminated(e);
    truncated[i] = !terminated[i] && e.step >= e.schedule.steps;
  };
  detail::run_jobs(count, threads, steps, control, job, s.workers.get());
}

std::int64_t Episodes::steps_taken(std::size_t i) const {
  check_index(i, impl_->episodes.size());
  return impl_->episodes[i].step;
}

double Episodes::time(std::size_t i) const {
  check_index(i, impl_->episodes.size());
  return impl_->episodes[i].data.get()->time;
}

std::vector<Warning> Episodes::warnings(std::size_t i) const {
  check_index(i, impl_->episodes.size());
  return impl_->episodes[i].health.warnings();
}

}  // namespace simloop
