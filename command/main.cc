// sim_loop: parses flags, calls the library, reports. All simulation lives in
// simloop::run; this file only turns its results and errors into text and
// exit codes.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/ioctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>
#include <optional>
#include <cstdio>
#include <string>
#include <system_error>

#include "cli_options.hpp"
#include "simloop/control.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/model.hpp"
#include "simloop/output.hpp"
#include "simloop/output_lock.hpp"
#include "simloop/run.hpp"
#include "simloop/signals.hpp"
#include "simloop/sweep.hpp"
#include "simloop/version.hpp"

extern char** environ;

namespace {

constexpr int kExitRunFailed = 1;
constexpr int kExitUsage = 2;
// A terminating signal (SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE, ...:
// simloop::kTerminatingSignals) stops the work: exit 128 + the signal's
// number, as a shell reports a process the signal ended (130 for Ctrl-C, 143
// for SIGTERM, 129 for SIGHUP).
constexpr int kExitSignalBase = 128;

// A progress bar on stderr while the work runs, when stderr is a terminal
// (and TERM is not "dumb"): drawn from RunControl's poll (on the main thread,
// at most every 20 ms), shown once the work has taken kDelay, redrawn at most
// every kRedraw, and erased (finish()) before anything else is printed, so
// stdout and the output files are the same with or without it.
class TerminalProgress {
 public:
  static bool wanted() {
    const char* term = std::getenv("TERM");
    return ::isatty(STDERR_FILENO) == 1 && !(term && std::strcmp(term, "dumb") == 0);
  }

  // From here on the bar may be drawn (after the banner, before the work).
  void start() {
    if (!wanted()) return;
    winsize size{};
    columns_ = ::ioctl(STDERR_FILENO, TIOCGWINSZ, &size) == 0 && size.ws_col > 0 ? size.ws_col : 80;
    started_ = std::chrono::steady_clock::now();
    active_ = true;
  }

  void draw(std::int64_t done, std::int64_t total) {
    if (!active_ || total <= 0) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - started_ < kDelay || (drawn_ && now - last_draw_ < kRedraw)) return;
    last_draw_ = now;
    const double fraction = std::min(1.0, static_cast<double>(done) / static_cast<double>(total));
    char counts[96];
    std::snprintf(counts, sizeof counts, "] %3d%% %lld/%lld steps", static_cast<int>(fraction * 100.0),
                  static_cast<long long>(done), static_cast<long long>(total));
    const std::string head = "sim_loop [";
    const int room = columns_ - 1 - static_cast<int>(head.size() + std::strlen(counts));
    const int width = std::max(0, std::min(room, 40));
    const int filled = static_cast<int>(fraction * width);
    std::string line = "\r" + head + std::string(static_cast<size_t>(filled), '#') +
                       std::string(static_cast<size_t>(width - filled), '.') + counts + "\033[K";
    write_all(line);
    drawn_ = true;
  }

  // Erases the bar (the line is left empty, the cursor at its start); no
  // more drawing after this.
  void finish() {
    active_ = false;
    if (drawn_) write_all("\r\033[K");
    drawn_ = false;
  }

 private:
  static constexpr std::chrono::milliseconds kDelay{250};
  static constexpr std::chrono::milliseconds kRedraw{100};

  static void write_all(const std::string& text) {
    for (size_t at = 0; at < text.size();) {
      const ssize_t n = ::write(STDERR_FILENO, text.data() + at, text.size() - at);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return;  // a terminal that went away: no bar, nothing else to do
      at += static_cast<size_t>(n);
    }
  }

  bool active_ = false;
  bool drawn_ = false;
  int columns_ = 80;
  std::chrono::steady_clock::time_point started_, last_draw_;
};
TerminalProgress g_progress;

// The command's one control: a terminating signal requests a stop, the loops
// throw Interrupted within a chunk of steps, and the outputs' temporary files
// go with the stack. Made at startup, on the main thread (its owner). Its
// poll draws the progress bar; without a terminal there is no poll at all,
// so the loop does not even read the clock for it.
simloop::RunControl g_control = TerminalProgress::wanted()
                                    ? simloop::RunControl([](std::int64_t done, std::int64_t total) {
                                        g_progress.draw(done, total);
                                      })
                                    : simloop::RunControl();
volatile std::sig_atomic_t g_signal = 0;
// Set while nothing is half-done (no temporary file exists): loading the
// model, which cannot be stopped between chunks, ends the process at once.
volatile std::sig_atomic_t g_exit_at_once = 0;
// Set once this run's outputs are in place (a stop after that keeps them).
bool g_outputs_written = false;

extern "C" void on_stop_signal(int sig) {
  if (g_signal == 0) g_signal = sig;
  if (g_exit_at_once) {
    // Only async-signal-safe calls: write(2) of fixed pieces, then _exit.
    const auto put = [](const char* text) {
      [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, text, std::strlen(text));
    };
    put("sim_loop: interrupted (");
    put(simloop::signal_name(sig));
    put("); nothing was written\n");
    ::_exit(kExitSignalBase + sig);
  }
  g_control.request_stop();
}

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  // While the handler runs, the other terminating signals wait: the first
  // one names the stop.
  for (int sig : simloop::kTerminatingSignals) sigaddset(&action.sa_mask, sig);
  action.sa_flags = SA_RESTART;
  for (int sig : simloop::kTerminatingSignals) {
    // A signal we were started ignoring stays ignored (a shell's background
    // job, nohup), as Python and the shell's own tools leave it.
    struct sigaction inherited {};
    if (::sigaction(sig, nullptr, &inherited) == 0 && inherited.sa_handler == SIG_IGN) continue;
    ::sigaction(sig, &action, nullptr);
  }
  // Past a file-size limit (ulimit -f), write() fails with EFBIG, which we
  // report, instead of the process being killed with its temporary files.
  ::signal(SIGXFSZ, SIG_IGN);
}

// A closed stdin, stdout or stderr would make the next file we open take its
// number, and the report would land in an output file: keep 0, 1 and 2 open
// (on /dev/null). Returns false if stdout was closed.
bool keep_standard_streams_open() {
  bool stdout_open = true;
  for (int fd = 0; fd <= 2; ++fd) {
    if (::fcntl(fd, F_GETFD) == -1 && errno == EBADF) {
      if (fd == STDOUT_FILENO) stdout_open = false;
      const int null = ::open("/dev/null", O_RDWR);  // takes the lowest free number: fd
      if (null >= 0 && null != fd) ::close(null);
    }
  }
  return stdout_open;
}

// The report must reach stdout (a full disk, /dev/full): a run whose report
// was lost exits 1, with one line on stderr, unless it already failed.
int finish_stdout(int code) {
  errno = 0;
  const bool failed = std::fflush(stdout) != 0 || std::ferror(stdout) != 0;
  const int err = errno;
  if (failed && code == 0) {
    std::fprintf(stderr, "sim_loop: cannot write the report to standard output (%s)\n",
                 err != 0 ? std::strerror(err) : "write error");
    return kExitRunFailed;
  }
  return code;
}

// One line on stderr, whatever the message held (MuJoCo's XML errors span lines).
int fail(int code, const std::string& message) {
  g_progress.finish();
  std::fprintf(stderr, "sim_loop: %s\n", simloop::one_line(message).c_str());
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

// The line and exit code for a stop on a terminating signal.
int interrupted() {
  const int sig = g_signal != 0 ? g_signal : SIGINT;
  return fail(kExitSignalBase + sig, std::string("interrupted (") + simloop::signal_name(sig) + "); " +
                                         (g_outputs_written ? "after the outputs were written"
                                                            : "the earlier outputs were left as they were"));
}

// Stops early if a signal asked to: the work so far is dropped.
void check_stop() {
  if (g_control.stop_requested()) throw simloop::Interrupted("interrupted");
}

// --plot: the chart is drawn by the Python package (matplotlib), which reads
// the CSV just written. The interpreter: $SIMLOOP_PYTHON if set, else the one
// CMake recorded (the project's .venv, which scripts/test.sh makes).
int plot_with_python(const std::filesystem::path& out, const char* what) {
  const char* env = std::getenv("SIMLOOP_PYTHON");
  const std::string python = env && *env ? env : SIMLOOP_DEFAULT_PYTHON;
  const std::string out_text = out.string();
  const char* argv[] = {python.c_str(), "-m", "simloop", "plot", what, "--out", out_text.c_str(), nullptr};
  // Its stderr comes back through a pipe: a failure is reported in our one
  // line (its last line, a traceback's verdict), not as a traceback and ours.
  int err_pipe[2];
  if (::pipe2(err_pipe, O_CLOEXEC) != 0) {
    return fail(kExitRunFailed, "--plot: cannot start " + python + " (" + std::strerror(errno) + ")");
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, err_pipe[1], STDERR_FILENO);
  // Its own process group, so that a stop ends it and anything it started.
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attributes, 0);
  pid_t pid = 0;
  std::fflush(stdout);
  const int spawned =
      posix_spawnp(&pid, python.c_str(), &actions, &attributes, const_cast<char* const*>(argv), environ);
  posix_spawnattr_destroy(&attributes);
  posix_spawn_file_actions_destroy(&actions);
  ::close(err_pipe[1]);
  if (spawned != 0) {
    ::close(err_pipe[0]);
    return fail(kExitRunFailed, "--plot: cannot start " + python + " (scripts/test.sh installs the simloop package "
                                "into the project's .venv; or set SIMLOOP_PYTHON to a Python that has it)");
  }
  // Read its stderr until it exits (not until the pipe's end: something it
  // started may hold that open); on a stop, end its process group.
  std::string err_text;
  int status = 0;
  bool exited = false, stopped = false;
  while (!exited) {
    if (g_control.stop_requested() && !stopped) {
      ::kill(-pid, SIGTERM);
      stopped = true;
    }
    pollfd p{err_pipe[0], POLLIN, 0};
    if (::poll(&p, 1, 20) > 0) {
      char buf[4096];
      const ssize_t n = ::read(err_pipe[0], buf, sizeof buf);
      if (n > 0 && err_text.size() < (1u << 16)) err_text.append(buf, static_cast<size_t>(n));
    }
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    exited = done == pid || (done < 0 && errno != EINTR);
  }
  // What it wrote just before exiting, without waiting for the pipe's end.
  ::fcntl(err_pipe[0], F_SETFL, O_NONBLOCK);
  for (char buf[4096]; err_text.size() < (1u << 16);) {
    const ssize_t n = ::read(err_pipe[0], buf, sizeof buf);
    if (n <= 0) break;
    err_text.append(buf, static_cast<size_t>(n));
  }
  ::close(err_pipe[0]);
  check_stop();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string last;  // its last non-empty line
    const size_t end = err_text.find_last_not_of(" \r\n");
    if (end != std::string::npos) {
      const size_t newline = err_text.find_last_of('\n', end);
      const size_t begin = newline == std::string::npos ? 0 : newline + 1;
      last = err_text.substr(begin, end - begin + 1);
    }
    if (last.rfind("sim-loop: ", 0) == 0) last.erase(0, 10);
    return fail(kExitRunFailed, "--plot: " + python + " -m simloop plot failed" +
                                    (last.empty() ? std::string() : ": " + last) +
                                    " (the outputs above were written; the plot needs the simloop package and "
                                    "matplotlib; scripts/test.sh installs both into the project's .venv)");
  }
  return 0;
}

// A sweep's outputs: sweep.csv put in place, the summary, the plot if asked.
int report_sweep(const simloop::cli::Options& opts, const std::string& csv_text, const std::string& summary) {
  const std::filesystem::path csv = opts.out / "sweep.csv";
  simloop::PendingFile file(csv);
  file.append(csv_text);
  file.finish();
  simloop::commit_together({&file}, &g_control);
  g_outputs_written = true;
  g_progress.finish();
  std::fputs(summary.c_str(), stdout);
  std::printf("sweep: %s\n", csv.c_str());
  if (opts.plot) {
    const int status = plot_with_python(opts.out, "sweep");
    if (status != 0) return status;
    std::printf("plot: %s\n", (opts.out / "sweep.png").c_str());
  }
  return 0;
}

int sweep_command(const simloop::cli::Options& opts, const simloop::Model& model) {
  const simloop::SweepResult result =
      simloop::sweep(model, opts.sweep_timesteps, opts.sweep_duration, opts.threads, &g_control);
  return report_sweep(opts, simloop::sweep_csv(result), simloop::sweep_summary(result));
}

// sweep --scenario, --body, --ctrl: the scenario at every timestep.
int scenario_sweep_command(const simloop::cli::Options& opts, const simloop::Scenario& scenario,
                           const simloop::Model& scene) {
  const simloop::ScenarioSweepResult result =
      simloop::sweep_scenario(scene, scenario, opts.sweep_timesteps, opts.sweep_duration,
                              simloop::cli::scenario_config(opts), opts.threads, &g_control);
  return report_sweep(opts, simloop::scenario_sweep_csv(result), simloop::scenario_sweep_summary(result));
}

int run_command(const simloop::cli::Options& opts, const simloop::Model& model) {
  // The trajectory goes to its file as the loop steps, so memory stays
  // bounded however long the run; both outputs are put in place together at
  // the end, or (an error, a signal) neither.
  simloop::OutputWriter writer(opts.out);
  simloop::Data workspace(model);
  const simloop::RunResult result = simloop::run(model, opts.run, workspace, &writer.trajectory(), &g_control);
  const simloop::OutputFiles files = writer.commit(result.metrics, &g_control);
  g_outputs_written = true;
  g_progress.finish();
  std::fputs(simloop::summary_text(result).c_str(), stdout);
  std::printf("metrics: %s\n", files.metrics.c_str());
  std::printf("trajectory: %s (%lld rows)\n", files.trajectory.c_str(), static_cast<long long>(result.rows));
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

// A scenario's run (--scenario, --body, --ctrl): the same streaming and
// committing as the chapter's, with the scenario's columns and metrics.
int scenario_command(const simloop::cli::Options& opts, const simloop::Scenario& scenario,
                     const simloop::Model& scene) {
  simloop::OutputWriter writer(opts.out);
  const simloop::ScenarioRunResult result = simloop::run_scenario(
      scene, scenario, simloop::cli::scenario_config(opts), nullptr, &writer.trajectory(), &g_control);
  const simloop::OutputFiles files = writer.commit(simloop::scenario_metrics_json(result), &g_control);
  g_outputs_written = true;
  g_progress.finish();
  std::fputs(simloop::scenario_summary(result).c_str(), stdout);
  std::printf("metrics: %s\n", files.metrics.c_str());
  std::printf("trajectory: %s (%lld rows, %zu columns)\n", files.trajectory.c_str(),
              static_cast<long long>(result.rows), result.columns.size());
  if (opts.rerun) {
    std::printf("recording: none (sim_loop writes no .rrd; python -m simloop records one)\n");
  }
  return 0;
}

int run_main(int argc, char** argv) {
  const auto started = std::chrono::steady_clock::now();
  namespace cli = simloop::cli;
  if (!keep_standard_streams_open()) {
    return fail(kExitRunFailed, "standard output is closed; nothing was run (the report would be lost)");
  }
  install_signal_handlers();
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
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    return fail(kExitRunFailed, std::string("cannot write the report to standard output (") + std::strerror(errno) +
                                    "); nothing was run");
  }

  // Inputs first, so that a bad one costs nothing and changes nothing. A
  // signal while the model loads ends the process at once: nothing is
  // half-written yet.
  std::optional<simloop::Model> model;
  std::optional<simloop::Scenario> scenario;
  g_exit_at_once = 1;
  if (g_signal != 0) on_stop_signal(g_signal);
  if (!opts.scenario_path.empty()) {
    try {
      scenario = simloop::Scenario::from_toml_file(opts.scenario_path);
    } catch (const simloop::Error& e) {
      g_exit_at_once = 0;
      return fail(kExitUsage, "--scenario: " + std::string(e.what()));
    }
  }
  const std::string model_flag = scenario ? "--scenario " + opts.scenario_path
                                 : opts.model_path.empty() ? "--model" : "--model " + opts.model_path;
  try {
    model = scenario                   ? simloop::load_scene(*scenario)
            : opts.model_path.empty() ? simloop::Model::pusher_scene()
                                      : simloop::Model::from_file(opts.model_path);
  } catch (const simloop::Error& e) {
    g_exit_at_once = 0;
    const bool theirs = scenario ? !scenario->scene.empty() : !opts.model_path.empty();
    return fail(theirs ? kExitUsage : kExitRunFailed, (scenario ? "--scenario: " : "--model: ") + std::string(e.what()));
  } catch (const std::bad_alloc&) {
    g_exit_at_once = 0;
    return fail(kExitRunFailed, model_flag + ": out of memory while loading the model");
  } catch (const std::exception& e) {
    g_exit_at_once = 0;
    return fail(kExitRunFailed, model_flag + ": while loading the model: " + e.what());
  }
  // What MuJoCo said while it loaded the scene, as it says what it warns
  // while stepping: on the report.
  std::fputs(simloop::load_warnings_text(*model).c_str(), stdout);
  // What runs: a scenario (its names checked now, in the flags' words), or
  // the chapter's loop, which needs the chapter's box and pusher.
  try {
    if (opts.is_scenario() && !scenario) scenario = simloop::cli::scenario_from_flags(opts, &*model);
    simloop::cli::check_run_inputs(opts, *model, scenario ? &*scenario : nullptr);
  } catch (const std::exception& e) {
    g_exit_at_once = 0;
    return fail(kExitUsage, e.what());
  }
  // From here on a file may exist that must go (the output directory's
  // probe, then the temporary outputs): a signal only requests a stop.
  g_exit_at_once = 0;
  std::error_code out_check;
  const bool out_existed = std::filesystem::exists(opts.out, out_check);
  // The run holds --out's lock for the rest of its life (one run at a time
  // in a folder); declared first, it is released last, after the folder's
  // removal below.
  std::optional<simloop::OutputLock> out_lock;
  // A folder this run makes goes again if the run leaves nothing in it (a
  // failed or interrupted run): remove() takes only an empty directory.
  struct RemoveIfLeftEmpty {
    std::filesystem::path dir;
    ~RemoveIfLeftEmpty() {
      std::error_code ignored;
      if (!dir.empty()) std::filesystem::remove(dir, ignored);
    }
  } made{out_existed ? std::filesystem::path() : opts.out};
  try {
    simloop::prepare_output_dir(opts.out);
    out_lock.emplace(opts.out);
  } catch (const simloop::OutputInUse& e) {
    made.dir.clear();  // the other run's folder now
    return fail(kExitUsage, "--out: " + std::string(e.what()));
  } catch (const std::exception& e) {
    return fail(kExitUsage, "--out: " + std::string(e.what()));
  }

  // For error lines: what ran, with the timestep and steps it ran with.
  const auto doing_now = [&] { return simloop::cli::doing(opts, &*model, scenario ? &*scenario : nullptr); };
  try {
    check_stop();
    g_progress.start();
    const bool sweeping = opts.command == cli::Command::kSweep;
    const int status = sweeping && scenario ? scenario_sweep_command(opts, *scenario, *model)
                       : sweeping           ? sweep_command(opts, *model)
                       : scenario           ? scenario_command(opts, *scenario, *model)
                                            : run_command(opts, *model);
    if (status != 0) return status;
  } catch (const simloop::Interrupted&) {
    return interrupted();
  } catch (const simloop::MujocoError& e) {
    return fail(kExitRunFailed, "MuJoCo error while " + doing_now() + ": " + e.what());
  } catch (const simloop::Error& e) {  // IoError names its file; InvalidArgument its input
    return fail(kExitRunFailed, e.what());
  } catch (const std::bad_alloc&) {
    return fail(kExitRunFailed, "out of memory while " + doing_now());
  } catch (const std::system_error& e) {  // threads that cannot be made, for one
    return fail(kExitRunFailed, "while " + doing_now() + ": " + e.what());
  } catch (const std::exception& e) {
    return fail(kExitRunFailed, "while " + doing_now() + ": " + e.what());
  }
  if (g_control.stop_requested()) return interrupted();  // after the outputs were put in place
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::printf("wall-clock: %.1f ms, peak memory: %.1f MiB\n", seconds * 1e3, peak_memory_mib());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int code = kExitRunFailed;
  try {
    code = run_main(argc, argv);
  } catch (...) {  // a bug, but never a crash: say so in one line
    code = fail(kExitRunFailed, "internal error (please report it)");
  }
  return finish_stdout(code);
}
