#include "simloop/episode.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "mujoco_compat.hpp"
#include "run_detail.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/rows.hpp"
#include "simloop/scene_params.hpp"
#include "simloop/shove.hpp"
#include "stepper.hpp"
#include "worker_pool.hpp"

namespace simloop {

namespace {

// One episode: its own Data, the schedule drawn at its reset, where it is.
struct Episode {
  Episode(const Model& shared, bool observe_acceleration)
      : model(shared), data(shared), core(shared.get(), observe_acceleration) {}
  Model model;  // the shared one, or a copy with this episode's scene parameters (the same sizes)
  Data data;
  Schedule schedule;
  std::optional<ScheduledInputs> inputs;  // empty until the first reset
  std::int64_t step = 0;
  detail::Stepper core;
};

// What an episode does around each physics step: its scheduled inputs
// (the disturbances; ctrl is the actions').
struct EpisodeInputs : detail::StepHooks {
  explicit EpisodeInputs(ScheduledInputs& scheduled) : inputs(scheduled) {}
  void before_step(std::int64_t step, mjData* d) noexcept { inputs.write(step, d); }
  ScheduledInputs& inputs;
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
  bool observe_acceleration = false;
  // Each episode's start being made (stage_reset), apart from the episode
  // until commit_reset swaps it in: made at the first stage, kept.
  std::vector<std::unique_ptr<Episode>> staged;
  std::vector<bool> stage_ready;  // staged[i] holds a start not yet committed

  // Episode e started afresh from `seed` (reset's first part: its state, not its observation).
  void start(Episode& e, std::uint64_t seed, const ResetSpec* reset) const;
  // The start's first observation (reset's second part).
  void first_observation(Episode& e, double* observation) const;
  // Episode i's staged start, or InvalidArgument.
  [[nodiscard]] Episode& staged_episode(std::size_t i) const;
  std::unique_ptr<detail::WorkerPool> workers = std::make_unique<detail::WorkerPool>();  // kept from step to step

  // The row for the state entering the episode's next step: the inputs
  // scheduled for it written, then what MuJoCo derives from the state.
  void observe(Episode& e, double* observation) const {
    const mjModel* m = e.model.get();
    mjData* d = e.data.get();
    if (e.step < e.schedule.steps) e.inputs->write(e.step, d);
    e.core.observe(m, d, e.step);
    recorder->before_step(observation, e.step, m, d, true, e.core.entering_ncon(d));
    recorder->after_step(observation, m, d);
  }

  // The data columns as the reset or the last step left d (read_data_at_step).
  void read_data(Episode& e, double* observation, bool stepped) const {
    const mjModel* m = e.model.get();
    mjData* d = e.data.get();
    detail::guarded_steps(m, e.step, e.step, [&] { recorder->read_data(observation, m, d, stepped); });
  }

  [[nodiscard]] bool terminated(const Episode& e) const noexcept { return e.core.health().broken(); }
};

Episodes::Episodes(const Model& scene, const Scenario& scenario, const ScenarioConfig& config, std::size_t count,
                   bool read_state)
    : impl_(std::make_unique<Impl>(Impl{scene.for_run(run_timestep(scene, scenario, config), false),
                                        detail::configured_scenario(scenario, config),
                                        config,
                                        {},
                                        std::nullopt,
                                        0,
                                        {},
                                        false,
                                        {},
                                        {}})) {
  Impl& s = *impl_;
  s.resolved = resolve(s.scenario, s.model.get());
  // The columns depend on which bodies are disturbed, not on the draws.
  const std::unique_ptr<Draws> draws = make_draws(0, config.rng);
  const Schedule schedule = build_schedule(s.resolved, s.scenario, s.model.timestep(), *draws);
  detail::check_schedule_run(schedule.steps, 1);
  s.recorder.emplace(s.model.get(), s.resolved, schedule);
  s.length = schedule.steps;
  s.observe_acceleration = read_state || s.recorder->reads_acceleration_stage();
  s.staged.resize(count);
  s.stage_ready.assign(count, false);
  s.episodes.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    s.episodes.emplace_back(s.model, s.observe_acceleration);
    if (i == 0) check_episodes_memory(count, detail::compat::data_bytes(s.episodes.front().data.get()));
  }
}

Episodes::~Episodes() = default;

std::size_t Episodes::count() const noexcept { return impl_->episodes.size(); }
int Episodes::nu() const noexcept { return detail::compat::as_int(impl_->model.get()->nu); }
int Episodes::width() const noexcept { return impl_->recorder->width(); }
const std::vector<Column>& Episodes::columns() const noexcept { return impl_->recorder->columns(); }
const Model& Episodes::model() const noexcept { return impl_->model; }

const Scenario& Episodes::scenario() const noexcept { return impl_->scenario; }

std::int64_t Episodes::steps() const noexcept { return impl_->length; }

namespace {
void check_index(std::size_t i, std::size_t count) {
  if (i >= count) {
    throw InvalidArgument("episode " + std::to_string(i) + " does not exist: there are " + std::to_string(count));
  }
}

// mjData's array `name` of e, filled first if MuJoCo fills it only on request.
FieldView field_of(Episode& e, std::string_view name) {
  FieldView field = simloop::data_field(e.model.get(), e.data.get(), name);
  if (filled_on_request(name)) {
    detail::mujoco_call([&] { fill_derived(e.model.get(), e.data.get(), name); });
  }
  return field;
}
}  // namespace

void Episodes::Impl::start(Episode& e, std::uint64_t seed, const ResetSpec* reset) const {
  Scenario scenario_for_reset;
  const Scenario* spec = &scenario;
  if (reset != nullptr) {  // this episode's start instead of the scenario's
    check_reset(resolved, *reset, model.get());
    scenario_for_reset = scenario;
    scenario_for_reset.reset = *reset;
    spec = &scenario_for_reset;
  }
  const std::unique_ptr<Draws> draws = make_draws(seed, config.rng);
  Schedule schedule = build_schedule(resolved, *spec, model.timestep(), *draws);
  Model with_params = with_scene_params(model, schedule.start.params);
  e.schedule = std::move(schedule);
  e.model = std::move(with_params);
  e.inputs.emplace(e.schedule, false);  // ctrl is the actions'
  e.step = 0;
  e.core.reset(e.model.get(), e.data.get(), {-1, &e.schedule.start});  // as run_loop starts
}

void Episodes::Impl::first_observation(Episode& e, double* observation) const {
  if (recorder->data_at_step()) read_data(e, observation, false);
  observe(e, observation);
}

void Episodes::reset(std::size_t i, std::uint64_t seed, double* observation, const ResetSpec* reset) {
  Impl& s = *impl_;
  check_index(i, s.episodes.size());
  Episode& e = s.episodes[i];
  s.start(e, seed, reset);
  s.first_observation(e, observation);
}

void Episodes::stage_reset(std::size_t i, std::uint64_t seed, const ResetSpec* reset) {
  Impl& s = *impl_;
  check_index(i, s.episodes.size());
  std::unique_ptr<Episode>& staged = s.staged[i];
  if (!staged) {
    const std::size_t made = static_cast<std::size_t>(std::count_if(
        s.staged.begin(), s.staged.end(), [](const std::unique_ptr<Episode>& e) { return e != nullptr; }));
    check_episodes_memory(s.episodes.size() + made + 1, detail::compat::data_bytes(s.episodes.front().data.get()));
    staged = std::make_unique<Episode>(s.model, s.observe_acceleration);
  }
  s.stage_ready[i] = false;
  s.start(*staged, seed, reset);
  s.stage_ready[i] = true;
}

Episode& Episodes::Impl::staged_episode(std::size_t i) const {
  if (i >= staged.size() || !staged[i] || !stage_ready[i]) {
    throw InvalidArgument("episode " + std::to_string(i) + " has no start staged: stage_reset it first");
  }
  return *staged[i];
}

FieldView Episodes::staged_field(std::size_t i, std::string_view name) {
  return field_of(impl_->staged_episode(i), name);
}

const Model& Episodes::staged_model(std::size_t i) const { return impl_->staged_episode(i).model; }

void Episodes::commit_reset(std::size_t i, double* observation) {
  Impl& s = *impl_;
  Episode& e = s.staged_episode(i);
  mjData* d = e.data.get();
  const mjModel* m = e.model.get();
  // What the caller wrote, made consistent: quaternions unit as a given
  // qpos's are, then everything MuJoCo derives from the start. The warning
  // counters stay as the reset left them (the first step derives it again).
  detail::guarded_steps(m, 0, 0, [&] {
    mj_normalizeQuat(m, d->qpos);
    detail::derive_uncounted(m, d);
  });
  s.first_observation(e, observation);
  std::swap(s.episodes[i], e);  // the episode as it was is the next stage's
  s.stage_ready[i] = false;
}

const Schedule::Start& Episodes::start(std::size_t i) const {
  check_index(i, impl_->episodes.size());
  return impl_->episodes[i].schedule.start;
}

const Model& Episodes::model(std::size_t i) const {
  check_index(i, impl_->episodes.size());
  return impl_->episodes[i].model;
}

const mjData* Episodes::data(std::size_t i) const {
  check_index(i, impl_->episodes.size());
  return impl_->episodes[i].data.get();
}

FieldView Episodes::data_field(std::size_t i, std::string_view name) {
  check_index(i, impl_->episodes.size());
  return field_of(impl_->episodes[i], name);
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
    // The first step is the rest of the one the observation began.
    e.core.run(m, d, e.step, e.step + steps[i], EpisodeInputs(*e.inputs), &ctl, true);
    if (s.recorder->data_at_step()) s.read_data(e, observations + i * static_cast<std::size_t>(width), true);
    s.observe(e, observations + i * static_cast<std::size_t>(width));
    terminated[i] = s.terminated(e);
    truncated[i] = !terminated[i] && e.step >= e.schedule.steps;
  };
  detail::run_jobs(count, threads, steps, control, job, s.workers.get());
}

void Episodes::read_data_at_step(bool on) noexcept { impl_->recorder->read_data_at_step(on); }

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
  return impl_->episodes[i].core.health().warnings();
}

}  // namespace simloop
