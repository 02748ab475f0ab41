// Internals shared by the library's loops.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/recorder.hpp"
#include "simloop/scenario_run.hpp"

namespace simloop::detail {

// The default RowSink: keeps every row in a Trajectory.
class KeepRows final : public RowSink {
 public:
  explicit KeepRows(Trajectory& into) : into_(into) {}
  void start(int columns, std::int64_t rows) override { into_ = Trajectory(rows, columns); }
  void write(const double* rows, std::int64_t count) override {
    std::copy(rows, rows + count * into_.columns(), into_.mutable_row(next_));
    next_ += count;
  }

 private:
  Trajectory& into_;
  std::int64_t next_ = 0;
};

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

// Throws InvalidArgument unless steps and record_every are each from 1 to
// kMaxSteps / kMaxRecordEvery (run_schedule's own check).
void check_schedule_run(std::int64_t steps, std::int64_t record_every);

// run_schedule() with its recorder already made (a prepared run's).
[[nodiscard]] RunRecord run_schedule_with(const mjModel* m, mjData* d, const Recorder& recorder,
                                          const Schedule& schedule, std::int64_t record_every, RowSink* sink,
                                          RunControl* control, const RunInputs& inputs = {});

// The same without announcing its steps to the control (a batch announces
// all of its runs' steps up front), with `watching` observing every step too
// (loop.hpp), and the energy audit when the recorder has its columns.
// `d_is_reset`: d is as mj_resetData leaves it (run_loop).
class StepObserver;
[[nodiscard]] RunRecord run_schedule_counted_elsewhere(const mjModel* m, mjData* d, const Recorder& recorder,
                                                       const Schedule& schedule, std::int64_t record_every,
                                                       RowSink* sink, RunControl* control, const RunInputs& inputs = {},
                                                       const std::vector<StepObserver*>& watching = {},
                                                       bool d_is_reset = false);

// run_scenario(scene, scenario, config, &workspace, sink, control) with
// `watching` observing every step too, without announcing its steps to the
// control unless `announce`.
[[nodiscard]] RunRecord run_scenario_watched(const Model& scene, const Scenario& scenario, const ScenarioConfig& config,
                                             Data& workspace, RowSink* sink, RunControl* control,
                                             const std::vector<StepObserver*>& watching, bool announce);

// run_scenario_batch(..., sinks, threads, control, inputs) with watching[i]
// (empty, or one list per config) observing run i's steps too.
[[nodiscard]] std::vector<RunRecord> run_scenario_batch_watched(
    const Model& scene, const Scenario& scenario, const std::vector<ScenarioConfig>& configs,
    const std::vector<RowSink*>& sinks, int threads, RunControl* control, const std::vector<RunInputs>& inputs,
    const std::vector<std::vector<StepObserver*>>& watching);

// The same batch with each run's record handed to done(i, record) by the
// worker that ran it, as the run ends (from any worker thread, each i once),
// instead of kept in a list.
void for_each_scenario_run(const Model& scene, const Scenario& scenario, const std::vector<ScenarioConfig>& configs,
                           const std::vector<RowSink*>& sinks, int threads, RunControl* control,
                           const std::vector<RunInputs>& inputs,
                           const std::vector<std::vector<StepObserver*>>& watching,
                           const std::function<void(std::size_t i, RunRecord&& record)>& done);

// A scenario as one run of `config` sees it: its length replaced by
// config.steps, its disturbances dropped unless config.perturb.
[[nodiscard]] Scenario configured_scenario(const Scenario& scenario, const ScenarioConfig& config);

// A batch's checks before any run starts: threads (rows.hpp), and run i's
// own checks, their InvalidArgument prefixed "run i: ".
using simloop::check_threads;
template <class Check>
void check_run(std::size_t i, Check&& check) {
  try {
    check();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument("run " + std::to_string(i) + ": " + e.what());
  }
}

// The batches' worker pool: job(i, data, control) for every i in [0, jobs),
// taken in order from one atomic index by batch_workers(threads, jobs)
// workers, each with its own Data made for `model` (the calling thread is
// worker 0). steps[i], job i's steps, are announced to the control
// (`control`, or one of its own) up front. If threads cannot be started,
// fewer workers do the work. While the others finish, the calling thread
// keeps polling the control. Once a job throws, no new job starts; after all
// workers have stopped, a requested stop throws Interrupted, else the
// failure of the lowest index is rethrown.
void run_jobs(const Model& model, std::size_t jobs, int threads, const std::vector<std::int64_t>& steps,
              RunControl* control, const std::function<void(std::size_t job, Data& data, RunControl& control)>& job);

// The same for jobs that bring their own Data (Episodes): job(i, worker,
// control), worker in [0, batch_workers(threads, jobs)); on the threads of
// `kept` (worker_pool.hpp) when given, kept for the next call, else on
// threads started for this call.
class WorkerPool;
void run_jobs(std::size_t jobs, int threads, const std::vector<std::int64_t>& steps, RunControl* control,
              const std::function<void(std::size_t job, int worker, RunControl& control)>& job,
              WorkerPool* kept = nullptr);

// Tests only: from now on a batch can start at most `threads` more threads
// (as under a process limit, RLIMIT_NPROC); a negative count lifts the limit.
void limit_thread_starts_for_testing(int threads) noexcept;

}  // namespace simloop::detail
