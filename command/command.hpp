// The command's one orchestration, shared by sim_loop (main.cc) and python -m
// simloop (through the bindings): parse the flags, help and version, the
// banner, the inputs, the output folder and its lock, the run or the sweep,
// the report, and every failure as one line and an exit code. What differs
// between the two processes (their streams and signals, the progress bar,
// the recording, the plot) is a Host's.
#pragma once

#include <exception>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "cli_options.hpp"
#include "simloop/control.hpp"
#include "simloop/folder_run.hpp"

namespace simloop::cli {

inline constexpr int kExitRunFailed = 1;
inline constexpr int kExitUsage = 2;

// A failure a host's hook reports: its line and the exit code.
class Failure : public std::runtime_error {
 public:
  Failure(int exit_code, const std::string& line) : std::runtime_error(line), code(exit_code) {}
  int code;
};

// A recording made from a run as it streams its files (python -m simloop's
// rerun recording): a RunDrawing (folder_run.hpp) with the report's line for
// it. Destroyed unfinished (a failure, a signal), it abandons its file.
class Recording : public RunDrawing {
 public:
  // The report's line once the outputs are in place.
  [[nodiscard]] virtual std::string line() const = 0;
};

// What the two commands' processes do their own way.
class Host {
 public:
  virtual ~Host() = default;
  [[nodiscard]] virtual std::string help(bool sweep) const = 0;
  [[nodiscard]] virtual std::string version() const = 0;
  // The report, on standard output; throws if it cannot be written.
  virtual void print(std::string_view text) = 0;
  virtual void flush() = 0;
  // One line on standard error; returns `code`.
  virtual int fail(int code, const std::string& line) = 0;
  // While the inputs load (nothing written yet): a signal may end the
  // process at once.
  virtual void loading(bool /*now*/) {}
  // work(control) with the host's progress and stop, the bar gone when it
  // returns.
  virtual void work(const char* label, const std::function<void(RunControl*)>& work) = 0;
  // The outputs are in place: a stop after this keeps them.
  virtual void outputs_written() {}
  // The run's recording, or none (sim_loop records none).
  virtual std::unique_ptr<Recording> recording(const Options& /*opts*/, const Model& /*model*/,
                                               const Scenario* /*scenario*/) {
    return nullptr;
  }
  // --plot: draws out/<what>.png from out/<what>.csv and returns its path.
  virtual std::filesystem::path plot(const std::filesystem::path& out, const char* what) = 0;
  // A stop (Interrupted): the exit code, or the host's own exception.
  virtual int interrupted() = 0;
  // After the outputs are in place: the exit code of a stop asked for
  // meanwhile, else 0.
  virtual int stop_code() { return 0; }
  // An exception that is the host's own (Python's), to pass through as it is.
  [[nodiscard]] virtual bool passes_through(const std::exception_ptr& /*error*/) const { return false; }
};

// The whole command: `args` without the program's name. Returns the exit
// code; what it reports goes through `host`.
int run_command(const std::vector<std::string>& args, Host& host);

// VmHWM of this process, MiB (-1 if unknown): the report's peak memory.
[[nodiscard]] double peak_memory_mib();

}  // namespace simloop::cli
