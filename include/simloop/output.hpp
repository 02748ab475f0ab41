// What a run leaves behind: metrics.json, trajectory.csv, and the summary
// lines the commands print. The library writes files only when asked to,
// always atomically, and the two outputs together: after any failure the
// directory holds all the old files or all the new ones, and no temporary
// file (only SIGKILL or a power cut can leave one).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include "simloop/control.hpp"
#include "simloop/output_lock.hpp"
#include "simloop/run.hpp"

namespace simloop {

// metrics.json: the text Python's json.dumps(metrics, indent=2,
// sort_keys=True) + "\n" writes, byte for byte, floats rounded to 6
// decimals. For the chapter's run (a RunResult, or its Metrics), the
// chapter's keys. For any other run, what its record holds: scenario, seed,
// rng, perturb, steps, timestep; bodies: each recorded body's final_pos (m)
// and final_speed (m/s); disturbances: each one's body, force (N) and
// torque (N m) as applied, start_step, steps (as they happened) and
// steps_asked; warnings: MuJoCo's and simloop's, by name, with their counts.
// (A RunResult passed as a RunRecord gets the latter: the chapter's run
// described as a scenario's.)
[[nodiscard]] std::string metrics_json(const Metrics& metrics);
[[nodiscard]] std::string metrics_json(const RunResult& result);
[[nodiscard]] std::string metrics_json(const RunRecord& record);

// trajectory.csv: a header of the column names (the chapter's,
// ChapterColumns::kNames, unless `columns` are given), then one line per
// row. Numbers are the shortest text that reads back as the same double;
// integer columns (step, ncon, contacts) are whole numbers; the final row's input cells
// are empty.
[[nodiscard]] std::string trajectory_csv(const Trajectory& trajectory, const std::vector<Column>& columns = {});

// The closing lines the commands print, each ending in "\n", nothing in
// them depending on time or machine. The chapter's: steps and sim time,
// where the box ended, the shove and its drift (or "no shove (baseline
// run)"; for the steps it acted, its window cut short when the run ends
// inside it), and any MuJoCo warnings. Any other run's: steps and sim time,
// where each recorded body ended, each disturbance as applied, warnings.
[[nodiscard]] std::string summary_text(const RunResult& result);
[[nodiscard]] std::string summary_text(const RunRecord& record);

// One summary line for a warning: "MuJoCo warning mjWARN_BADQACC: raised 3
// times, first in step 1043: ..." (or "simloop warning ..." for simloop's own).
[[nodiscard]] std::string warning_line(const Warning& warning);

// The warnings MuJoCo gave while it loaded `model` (Model::load_warnings), a
// line each: "MuJoCo warning while loading the model: ...\n"; "" if none.
[[nodiscard]] std::string load_warnings_text(const Model& model);

// Creates `dir` (and parents) if missing and checks that files can be
// created in it. Throws IoError naming the directory.
void prepare_output_dir(const std::filesystem::path& dir);

class PendingFile;

// Puts finished PendingFiles in place, all of them or none: every existing
// destination is first hard-linked to a backup name beside it (moved there
// on a filesystem without hard links), then each
// temporary file is renamed onto its destination; if one rename fails, the
// ones before it are rolled back from the backups (or removed, where there
// was no old file), so the directory holds all the old files or all the
// new ones. A destination that is a directory, or that cannot be replaced
// (an immutable file), fails before anything is renamed. The terminating
// signals (kTerminatingSignals, simloop/signals.hpp) are blocked in the
// calling thread during the renames, so a signal cannot cut the commit in half. With a `control` whose stop was
// requested, nothing is committed and Interrupted is thrown. Readers never
// see a half-written file. Throws IoError
// naming the destination that failed; the temporary files remain the
// PendingFiles' to remove.
void commit_together(const std::vector<PendingFile*>& files, const RunControl* control = nullptr);

// A file being written beside its destination: a temporary file
// ".<name>.tmp.XXXXXX" in the same directory, filled by append(), closed by
// finish(), and put in place by commit_together(). Until then the
// destination is untouched; the destructor removes the temporary file unless
// it was committed, so no error or exception leaves one behind. Throws
// IoError naming the destination.
class PendingFile {
 public:
  explicit PendingFile(std::filesystem::path target);
  PendingFile(const PendingFile&) = delete;
  PendingFile& operator=(const PendingFile&) = delete;
  ~PendingFile();

  // Writes all of `bytes` (write(2), retried on EINTR and short writes).
  void append(std::string_view bytes);
  // Makes the file an ordinary 0644 file and closes it; before committing.
  void finish();
  [[nodiscard]] const std::filesystem::path& target() const noexcept { return target_; }

 private:
  friend void commit_together(const std::vector<PendingFile*>& files, const RunControl* control);
  std::filesystem::path target_;
  std::string temp_;
  int fd_ = -1;
};

// Replaces `path` with `contents` atomically (a PendingFile committed): readers
// see the old file or the new, never a half-written one. Throws IoError
// naming the path; the old file is kept.
void write_file_atomically(const std::filesystem::path& path, std::string_view contents);

// A RowSink that writes trajectory.csv as the rows come, in bounded memory
// (a buffer of about kFlushBytes): the same bytes trajectory_csv() makes
// from the same rows. finish() writes what is buffered; an error writing
// (a full disk) throws IoError from write() or finish(), which stops a run.
class TrajectoryCsvSink final : public RowSink {
 public:
  static constexpr size_t kFlushBytes = size_t{1} << 16;
  // `columns`: the header and how to write each cell; empty for the
  // chapter's columns (as many as the run records).
  explicit TrajectoryCsvSink(PendingFile& file, std::vector<Column> columns = {})
      : file_(file), columns_(std::move(columns)) {}
  void describe(const std::vector<Column>& columns) override { columns_ = columns; }
  void start(int columns, std::int64_t rows) override;
  void write(const double* rows, std::int64_t count) override;
  void finish();

 private:
  PendingFile& file_;
  std::vector<Column> columns_;
  std::string buffer_;
};

struct OutputFiles {
  std::filesystem::path metrics;     // <dir>/metrics.json
  std::filesystem::path trajectory;  // <dir>/trajectory.csv
};

// A run's two outputs, written as the run goes: construct it (the directory
// is prepared and locked for this process, OutputLock, trajectory.csv's
// temporary file made), hand trajectory() to simloop::run as its RowSink,
// then commit() writes metrics.json's temporary file and puts both in place
// together (commit_together), with any finished files `also` given (the
// recording). Destroyed without a commit (an error, an Interrupted run) it
// removes its temporary files and leaves the earlier outputs as they were.
class OutputWriter {
 public:
  // `columns` as for TrajectoryCsvSink: empty for the chapter's.
  explicit OutputWriter(const std::filesystem::path& dir, std::vector<Column> columns = {});
  [[nodiscard]] RowSink& trajectory() noexcept { return csv_; }
  OutputFiles commit(const Metrics& metrics, const RunControl* control = nullptr,
                     const std::vector<PendingFile*>& also = {});
  // The same with metrics.json's text already made (a scenario's metrics).
  OutputFiles commit(std::string_view metrics_text, const RunControl* control = nullptr,
                     const std::vector<PendingFile*>& also = {});

 private:
  OutputFiles files_;
  OutputLock lock_;
  PendingFile trajectory_file_;
  TrajectoryCsvSink csv_;
};

// Writes metrics.json (as metrics_json above) and trajectory.csv of an
// in-memory result into `dir` (prepared first) through an OutputWriter:
// both or neither are replaced. InvalidArgument if its rows went to a
// RowSink when it ran (there are none to write).
OutputFiles write_outputs(const RunResult& result, const std::filesystem::path& dir);
OutputFiles write_outputs(const RunRecord& record, const std::filesystem::path& dir);

}  // namespace simloop
