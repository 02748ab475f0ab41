// sim_loop: parses flags, calls the library, reports. All simulation lives in
// simloop::run; this file only turns its results and errors into text and
// exit codes.
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <cstdio>
#include <string>

#include "cli_options.hpp"
#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/output.hpp"
#include "simloop/run.hpp"
#include "simloop/sweep.hpp"
#include "simloop/version.hpp"

extern char** environ;

namespace {

constexpr int kExitRunFailed = 1;
constexpr int kExitUsage = 2;

// One line on stderr, whatever the message held (MuJoCo's XML errors span lines).
int fail(int code, const std::string& message) {
  std::string line;
  bool pending_separator = false;
  for (char c : message) {
    if (c == '\n' || c == '\r') {
      pending_separator = !line.empty();
      continue;
    }
    if (pending_separator) {
      line += "; ";
      pending_separator = false;
    }
    line += c;
  }
  std::fprintf(stderr, "sim_loop: %s\n", line.c_str());
  return code;
}

// Peak resident memory of this process in MiB (VmHWM), or -1 if unknown.
// Read from /proc rather than getrusage: ru_maxrss also counts the memory of
// the process we were forked from, before our exec.
double peak_memory_mib() {
  std::FILE* status = std::fopen("/proc/self/status", "r");
  if (status == nullptr) return -1.0;
  char line[256];
  double kib = -1.0;
  while (std::fgets(line, sizeof line, status) != nullptr) {
    if (std::sscanf(line, "VmHWM: %lf kB", &kib) == 1) break;
  }
  std::fclose(status);
  return kib < 0 ? -1.0 : kib / 1024.0;
}

// --plot: the chart is drawn by the Python package (matplotlib), which reads
// the CSV just written. The interpreter: $SIMLOOP_PYTHON if set, else the one
// CMake recorded (the project's .venv, which scripts/test.sh makes).
int plot_with_python(const std::filesystem::path& out, const char* what) {
  const char* env = std::getenv("SIMLOOP_PYTHON");
  const std::string python = env && *env ? env : SIMLOOP_DEFAULT_PYTHON;
  const std::string out_text = out.string();
  const char* argv[] = {python.c_str(), "-m", "simloop", "plot", what, "--out", out_text.c_str(), nullptr};
  pid_t pid = 0;
  std::fflush(stdout);
  if (posix_spawnp(&pid, python.c_str(), nullptr, nullptr, const_cast<char* const*>(argv), environ) != 0) {
    return fail(kExitRunFailed, "--plot: cannot start " + python + " (scripts/test.sh installs the simloop package "
                                "into the project's .venv; or set SIMLOOP_PYTHON to a Python that has it)");
  }
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    return fail(kExitRunFailed, "--plot: " + python + " -m simloop plot failed (it needs the simloop package and "
                                "matplotlib; scripts/test.sh installs both into the project's .venv)");
  }
  return 0;
}

int sweep_command(const simloop::cli::Options& opts, const simloop::Model& model) {
  const simloop::SweepResult result =
      simloop::sweep(model, opts.sweep_timesteps, opts.sweep_duration, opts.threads);
  const std::filesystem::path csv = opts.out / "sweep.csv";
  simloop::write_file_atomically(csv, simloop::sweep_csv(result));
  std::fputs(simloop::sweep_summary(result).c_str(), stdout);
  std::printf("sweep: %s\n", csv.c_str());
  if (opts.plot) {
    const int status = plot_with_python(opts.out, "sweep");
    if (status != 0) return status;
    std::printf("plot: %s\n", (opts.out / "sweep.png").c_str());
  }
  return 0;
}

int run_command(const simloop::cli::Options& opts, const simloop::Model& model) {
  const simloop::RunResult result = simloop::run(model, opts.run);
  const simloop::OutputFiles files = simloop::write_outputs(result, opts.out);
  std::fputs(simloop::summary_text(result).c_str(), stdout);
  std::printf("metrics: %s\n", files.metrics.c_str());
  std::printf("trajectory: %s (%lld rows)\n", files.trajectory.c_str(),
              static_cast<long long>(result.trajectory.rows()));
  if (opts.rerun) {
    std::printf("recording: none (sim_loop writes no .rrd; python -m simloop records one)\n");
  }
  if (opts.plot) {
    const int status = plot_with_python(opts.out, "trajectory");
    if (status != 0) return status;
    std::printf("plot: %s\n", (opts.out / "trajectory.png").c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const auto started = std::chrono::steady_clock::now();
  namespace cli = simloop::cli;
  cli::Options opts;
  try {
    opts = cli::parse(argc, argv);
  } catch (const cli::UsageError& e) {
    return fail(kExitUsage, e.what());
  }
  if (opts.help && opts.command == cli::Command::kSweep) {
    std::fputs(cli::sweep_help_text("sim_loop").c_str(), stdout);
    return 0;
  }
  if (opts.help) {
    std::fputs(cli::help_text("sim_loop",
                              "accepted so the chapter's command lines work; sim_loop\n"
                              "                    writes no recording (python -m simloop does)")
                   .c_str(),
               stdout);
    return 0;
  }
  if (opts.version) {
    std::printf("sim_loop %s (%s)\n", simloop::kVersion, simloop::mujoco_version().c_str());
    return 0;
  }

  // Banner: the chapter's startup contract (tier; wall-clock comes at the end).
  std::printf("ch0.1-sim-loop | tier: cpu | %s | simloop %s\n", simloop::mujoco_version().c_str(),
              simloop::kVersion);
  std::fflush(stdout);

  // Inputs first, so that a bad one costs nothing and changes nothing.
  std::optional<simloop::Model> model;
  try {
    model = opts.model_path.empty() ? simloop::Model::pusher_scene()
                                    : simloop::Model::from_file(opts.model_path);
  } catch (const simloop::Error& e) {
    return fail(opts.model_path.empty() ? kExitRunFailed : kExitUsage, "--model: " + std::string(e.what()));
  }
  try {
    simloop::prepare_output_dir(opts.out);
  } catch (const simloop::Error& e) {
    return fail(kExitUsage, "--out: " + std::string(e.what()));
  }

  try {
    const int status = opts.command == cli::Command::kSweep ? sweep_command(opts, *model) : run_command(opts, *model);
    if (status != 0) return status;
  } catch (const simloop::Error& e) {
    return fail(kExitRunFailed, e.what());
  } catch (const std::exception& e) {  // out of memory, for one
    return fail(kExitRunFailed, e.what());
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::printf("wall-clock: %.1f ms, peak memory: %.1f MiB\n", seconds * 1e3, peak_memory_mib());
  return 0;
}
