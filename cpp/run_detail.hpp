// Internals shared by the library's loops.
#pragma once

#include <algorithm>

#include "simloop/run.hpp"

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

// Throws InvalidArgument if a run of `steps` steps keeping every
// `record_every`-th row of `columns` doubles would not fit the memory budget
// (trajectory_memory_budget), saying how much it needs and what to change.
void check_kept_rows(std::int64_t steps, std::int64_t record_every, int columns);

// run() without announcing its steps to the control: a batch announces all
// of its runs' steps up front, so progress has its true total from the start.
[[nodiscard]] RunResult run_counted_elsewhere(const Model& model, const RunConfig& config, Data& workspace,
                                              RowSink* sink, RunControl* control);

// Tests only: from now on run_batch can start at most `threads` more threads
// (as under a process limit, RLIMIT_NPROC); a negative count lifts the limit.
void limit_thread_starts_for_testing(int threads) noexcept;

}  // namespace simloop::detail
