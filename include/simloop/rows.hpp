// The vocabulary every run speaks: its rows and their columns, where the rows
// go, and the warnings it raised. Nothing here knows which scene or run.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace simloop {

// The ranges both faces (sim_loop's flags, Python's arguments) accept:
// steps and record_every from 1 to 2^62 - 1, so that no count the loop
// derives from them (rows, steps + K) can overflow an int64.
inline constexpr std::int64_t kMaxSteps = (std::int64_t{1} << 62) - 1;
inline constexpr std::int64_t kMaxRecordEvery = kMaxSteps;
// A batch's workers: threads from 1 to kMaxThreads, or 0 for one per core.
inline constexpr int kMaxThreads = 4096;

// A warning MuJoCo raised while stepping (mjData::warning). After some of
// them, a bad acceleration for one, MuJoCo resets the state and goes on, so
// a run that raised one did not simulate what its numbers seem to say.
struct Warning {
  std::string name;             // "mjWARN_BADQACC"
  std::int64_t count = 0;       // how many times it was raised in the run
  std::int64_t first_step = 0;  // the step during which it was first raised
  std::string message;          // MuJoCo's text for it, with the last info
};

// A run's recorded rows, stored row by row (the loop writes one row of
// adjacent doubles per step; separate column arrays cost the loop about 4%
// more time). Row k holds the state at the start of its step and the inputs
// written for that step; the final row (step == steps) has no inputs after
// it, so its input columns hold NaN. What each column is: Column, below.
class Trajectory {
 public:
  // Rows a run of `steps` steps records: every K-th step, then the final
  // state. Never overflows for steps, record_every in 1 .. kMaxSteps.
  [[nodiscard]] static std::int64_t rows_for(std::int64_t steps, std::int64_t record_every) noexcept {
    return steps / record_every + (steps % record_every != 0 ? 1 : 0) + 1;
  }

  Trajectory() = default;
  Trajectory(std::int64_t rows, int columns)
      : rows_(rows), columns_(columns), values_(static_cast<size_t>(rows) * static_cast<size_t>(columns)) {}

  [[nodiscard]] std::int64_t rows() const noexcept { return rows_; }
  [[nodiscard]] int columns() const noexcept { return columns_; }
  [[nodiscard]] double at(std::int64_t row, int column) const noexcept {
    return values_[static_cast<size_t>(row) * static_cast<size_t>(columns_) + static_cast<size_t>(column)];
  }
  // Row `row`: columns() adjacent values.
  [[nodiscard]] const double* row(std::int64_t row) const noexcept {
    return values_.data() + static_cast<size_t>(row) * static_cast<size_t>(columns_);
  }
  [[nodiscard]] double* mutable_row(std::int64_t row) noexcept {
    return values_.data() + static_cast<size_t>(row) * static_cast<size_t>(columns_);
  }
  // All rows() x columns() values, row-major.
  [[nodiscard]] const double* data() const noexcept { return values_.data(); }

 private:
  std::int64_t rows_ = 0;
  int columns_ = 0;
  std::vector<double> values_;
};

// One trajectory column, as the CSV writer and the bindings need it.
struct Column {
  std::string name;      // "box_x"; for scenarios made from the scene's names
  std::string unit;      // "m", "rad", "m/s", "N"; "" for counts and quaternions
  bool integer = false;  // a whole number (written without a decimal point)
  bool input = false;    // an input written for the step: the final row has none (NaN, an empty cell)
  // The recorded body whose 13 columns this is one of (x y z, qw qx qy qz,
  // vx vy vz, wx wy wz, in that order); "" for every other column.
  std::string body;
};

// The recorded bodies, by name, with the column of each one's "_x" (its 13
// columns follow: position, orientation, linear and angular velocity).
[[nodiscard]] std::map<std::string, std::size_t> recorded_bodies(const std::vector<Column>& columns);

// Where a run's trajectory rows go as the loop makes them: kept in memory
// (the result's trajectory, the default), streamed to a file by the
// commands, or reduced on the fly. The loop hands over rows in blocks
// between its chunks of steps, outside MuJoCo's C frames, so a sink may
// throw (a full disk): the run stops and the exception reaches the caller.
class RowSink {
 public:
  virtual ~RowSink() = default;
  // Once, before start(): what each column is.
  virtual void describe(const std::vector<Column>& /*columns*/) {}
  // Once, before any row: the width of every row and how many rows will come.
  virtual void start(int columns, std::int64_t rows) = 0;
  // `count` rows, each `columns` adjacent doubles, in order.
  virtual void write(const double* rows, std::int64_t count) = 0;
  // False: only the final row is wanted (a run with no observers then
  // records no other, and is given only that one).
  [[nodiscard]] virtual bool keeps_rows() const { return true; }
};

// A RowSink that keeps nothing: for runs whose metrics are all that is
// wanted (a run computes its metrics, final row and warnings whatever its
// sink), so a batch's memory does not grow with its runs' lengths. It holds
// no state, so one can serve every run of a batch at once.
class DiscardRows final : public RowSink {
 public:
  void start(int /*columns*/, std::int64_t /*rows*/) override {}
  void write(const double* /*rows*/, std::int64_t /*count*/) override {}
  [[nodiscard]] bool keeps_rows() const override { return false; }
};

// Rows to `first` and, if given, to `second` too (a run's trajectory.csv and
// its recording, say).
class TeeRows final : public RowSink {
 public:
  TeeRows(RowSink& first, RowSink* second) noexcept : first_(first), second_(second) {}
  void describe(const std::vector<Column>& columns) override {
    first_.describe(columns);
    if (second_) second_->describe(columns);
  }
  void start(int columns, std::int64_t rows) override {
    first_.start(columns, rows);
    if (second_) second_->start(columns, rows);
  }
  void write(const double* rows, std::int64_t count) override {
    first_.write(rows, count);
    if (second_) second_->write(rows, count);
  }

 private:
  RowSink& first_;
  RowSink* second_;
};

// How much memory the trajectories runs keep (no RowSink: Python's run,
// batches) may take: half of the least of the machine's physical memory,
// the cgroup's memory.max and the process's RLIMIT_AS / RLIMIT_DATA
// (ulimit -v / -d), in bytes. Runs over it are refused before they start
// rather than left to the allocator (which may only fail after minutes of
// stepping, or summon the OOM killer).
[[nodiscard]] std::uint64_t trajectory_memory_budget() noexcept;

// One run's kept trajectory: Trajectory::rows_for(steps, record_every) rows
// of `columns` doubles.
struct KeptRows {
  std::int64_t steps = 0;
  std::int64_t record_every = 1;
  int columns = 0;
  [[nodiscard]] std::uint64_t bytes() const noexcept;  // saturates at UINT64_MAX
};

// Throws InvalidArgument if runs that keep their trajectories in memory would
// together take more than `budget` bytes, saying how much they need and what
// to change: "steps 10000000000 with record_every 1 would keep 1.6 TiB of
// trajectory (22 columns) in memory (at most 11.6 GiB allowed: ...); raise
// record_every, or let sim_loop stream it to a file". For several runs (a
// batch) the sum is weighed and the message names the largest. Every run of
// the library that keeps its rows calls it before it allocates them.
void check_kept_rows(const std::vector<KeptRows>& runs, std::uint64_t budget = trajectory_memory_budget());

// Throws InvalidArgument unless threads is from 0 (one per core) to
// kMaxThreads. Every batch calls it before any run starts.
void check_threads(std::int64_t threads);

}  // namespace simloop
