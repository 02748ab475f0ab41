// sim_loop's flags: the chapter's, spelled and defaulted as there, plus
// --model, --record-every, --help and --version.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>
#include <string_view>

#include "simloop/run.hpp"

namespace simloop::cli {

enum class Command { kRun, kSweep };

struct Options {
  Command command = Command::kRun;
  RunConfig run;
  // `sweep`: the timesteps (empty: the default range), the span, the workers.
  std::vector<double> sweep_timesteps;
  double sweep_duration = 4.0;
  int threads = 0;         // 0: one per core
  bool plot = false;       // --plot: trajectory.png / sweep.png
  std::filesystem::path out = "outputs/ch0.1-sim-loop";
  std::string model_path;  // empty: the embedded pusher scene
  bool rerun = true;       // accepted for the chapter's command lines; sim_loop records nothing
  bool help = false;
  bool version = false;
};

// A bad command line. The message is one line naming the flag and the value.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Parses argv (argv[0] is skipped). Accepts "--flag value" and "--flag=value".
// Shared by sim_loop and `python -m simloop`, so both take the same flags and
// refuse bad ones with the same words.
[[nodiscard]] Options parse(int argc, const char* const* argv);

// --help for `program`; `recording` says what --rerun does there, `plot`
// what --plot does.
[[nodiscard]] std::string help_text(std::string_view program, std::string_view recording);
[[nodiscard]] std::string sweep_help_text(std::string_view program);

}  // namespace simloop::cli
