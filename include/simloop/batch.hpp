// Many runs over one compiled model: the chapter's "one model, many datas".
#pragma once

#include <vector>

#include "simloop/model.hpp"
#include "simloop/run.hpp"

namespace simloop {

// Runs every config on `model` with `threads` workers (0: one per core), each
// worker stepping its own Data; the model is shared read-only (one copy per
// distinct timestep, made before any worker starts). Each run resets its
// Data, so result i is bitwise identical to run(model, configs[i]), whatever
// the thread count. All configs are validated before any run starts
// (InvalidArgument naming the config's index); if runs fail, the failure of
// the lowest index is rethrown after all workers have stopped, no new run
// starts once one has failed, and the runs still going stop at their next
// chunk of steps (RunControl::abandon_batch). If threads cannot be created, fewer workers do
// the work (the results are the same). With a `control`, the batch can be
// stopped (Interrupted) and watched; its poll runs on the calling thread.
// Batches keep their runs' trajectories in memory: the whole batch is
// refused up front (InvalidArgument) if together they would not fit
// (check_kept_rows, summed over the runs).
[[nodiscard]] std::vector<RunResult> run_batch(const Model& model, const std::vector<RunConfig>& configs,
                                               int threads = 0, RunControl* control = nullptr);

// The same, with run i's rows going to sinks[i] instead of its result's
// trajectory (one non-null sink per config, each used by one worker at a
// time; a sink that reduces rows on the fly lets a batch of any length run
// in little memory).
[[nodiscard]] std::vector<RunResult> run_batch(const Model& model, const std::vector<RunConfig>& configs,
                                               const std::vector<RowSink*>& sinks, int threads = 0,
                                               RunControl* control = nullptr);

// The worker count run_batch uses for `threads` and `jobs`.
[[nodiscard]] int batch_workers(int threads, std::size_t jobs) noexcept;

}  // namespace simloop
