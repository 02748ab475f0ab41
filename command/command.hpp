// The command's one orchestration, shared by sim_loop (main.cc) and python -m
// simloop (simloop.__main__, through the bindings), as steps each process
// takes in order: parse the flags; the banner; load the inputs and check
// them; prepare the output folder and take its lock; the run or the sweep,
// its outputs written beside their places; put them in place (with what the
// process drew of the run, python -m simloop's recording); the report. Each
// step reports its failure as one line and an exit code (Failure) or a stop
// (Interrupted); what is not put in place goes with the Orchestration. The
// processes' own parts (streams, signals, the progress bar, the recording,
// the plot) are theirs: the Orchestration calls nothing back.
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_options.hpp"
#include "simloop/control.hpp"
#include "simloop/folder_run.hpp"
#include "simloop/output_lock.hpp"
#include "spooled_rows.hpp"

namespace simloop::cli {

inline constexpr int kExitRunFailed = 1;
inline constexpr int kExitUsage = 2;

// A failure as the command reports it: its line and the exit code.
class Failure : public std::runtime_error {
 public:
  Failure(int exit_code, const std::string& line) : std::runtime_error(line), code(exit_code) {}
  int code;
};

class Orchestration {
 public:
  // The flags parsed (Failure, kExitUsage, for a bad command line).
  explicit Orchestration(const std::vector<std::string>& args);
  Orchestration(const Orchestration&) = delete;
  Orchestration& operator=(const Orchestration&) = delete;
  ~Orchestration() { close(); }
  // What was not put in place goes: the temporary files, a folder this run
  // made and left empty, then the folder's lock. Once is enough.
  void close() noexcept;

  [[nodiscard]] const Options& options() const noexcept { return opts_; }
  [[nodiscard]] bool sweep() const noexcept { return opts_.command == Command::kSweep; }
  // The chapter's startup line (the tier; the wall-clock comes at the end).
  [[nodiscard]] static std::string banner();

  // Loads the scenario file and the scene: what MuJoCo warned while loading
  // it (the report's next lines). Nothing is written yet.
  std::string load();
  // Checks what is about to run against its scene, in the flags' words.
  void check();
  // Makes --out if missing and takes its lock for the Orchestration's life.
  void open_output();
  // The run or the sweep, its outputs written beside their places; with
  // `drawn`, a run keeps its rows for a drawing (drawn_rows()).
  void run(RunControl* control, bool drawn);
  // The outputs put in place together with `also`, all or none.
  void commit(const RunControl* control, const std::vector<PendingFile*>& also = {});
  [[nodiscard]] bool committed() const noexcept { return committed_; }

  [[nodiscard]] const Model& model() const { return *model_; }
  [[nodiscard]] const Scenario* scenario() const noexcept { return scenario_ ? &*scenario_ : nullptr; }
  // After run(): the chapter's result, or a scenario's (the other is null).
  [[nodiscard]] const RunResult* chapter_result() const noexcept { return chapter_ ? &*chapter_ : nullptr; }
  [[nodiscard]] const RunRecord* scenario_result() const noexcept { return record_ ? &*record_ : nullptr; }
  [[nodiscard]] SpooledRows* drawn_rows() noexcept { return drawn_.get(); }

  // After commit(): the report's lines, with the drawing's `drawn` (its
  // recording: none when empty).
  [[nodiscard]] std::string report(const std::string& drawn) const;
  // "plot: <path>", and the report's last line, wall-clock and peak memory.
  [[nodiscard]] static std::string plot_line(const std::filesystem::path& png);
  [[nodiscard]] std::string closing_line() const;
  // What the command was doing, for a failure's line.
  [[nodiscard]] std::string doing() const;

 private:
  template <class Step>
  void reporting(Step&& step);

  std::chrono::steady_clock::time_point started_;
  Options opts_;
  std::optional<Scenario> scenario_;
  std::optional<Model> model_;
  // --out's lock; declared before the folder, it is released after its removal.
  std::optional<OutputLock> out_lock_;
  std::filesystem::path made_;  // --out, if this run made it
  std::unique_ptr<SpooledRows> drawn_;
  std::optional<PendingOutputs> pending_;
  std::unique_ptr<PendingFile> sweep_csv_;
  std::optional<RunResult> chapter_;
  std::optional<RunRecord> record_;
  std::string sweep_summary_;
  OutputFiles files_;
  bool committed_ = false;
};

// VmHWM of this process, MiB (-1 if unknown): the report's peak memory.
[[nodiscard]] double peak_memory_mib();

}  // namespace simloop::cli
