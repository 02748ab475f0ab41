// What sim_loop's files share: its exit codes, its progress bar, the
// process's one RunControl and stop state (process.cc), its one-line
// failures, and --plot (plot.cc).
#pragma once

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "command.hpp"
#include "simloop/control.hpp"

namespace sim_loop {

using simloop::cli::kExitRunFailed;
using simloop::cli::kExitUsage;
// A terminating signal (SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE, ...:
// simloop::kTerminatingSignals) stops the work: exit 128 + the signal's
// number, as a shell reports a process the signal ended (130 for Ctrl-C, 143
// for SIGTERM, 129 for SIGHUP).
inline constexpr int kExitSignalBase = 128;

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
    char counts[128];
    const int written =
        std::snprintf(counts, sizeof counts, "] %3d%% %lld/%lld steps", static_cast<int>(fraction * 100.0),
                      static_cast<long long>(done), static_cast<long long>(total));
    // The time left at the rate so far, once there is a rate to go by.
    const double elapsed = std::chrono::duration<double>(now - started_).count();
    if (done > 0 && done < total && elapsed >= 1.0 && written > 0) {
      constexpr double kLongest = 9999 * 3600.0;  // shown as 9999:00:00; keeps the conversion defined
      const double left = elapsed * static_cast<double>(total - done) / static_cast<double>(done);
      const auto seconds = static_cast<long long>(std::min(left, kLongest));
      std::snprintf(counts + written, sizeof counts - static_cast<size_t>(written), ", %lld:%02lld:%02lld left",
                    seconds / 3600, seconds / 60 % 60, seconds % 60);
    }
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

// The process's state (defined in process.cc).
extern TerminalProgress g_progress;
extern simloop::RunControl g_control;
extern volatile std::sig_atomic_t g_signal;
extern volatile std::sig_atomic_t g_exit_at_once;
extern bool g_outputs_written;

// process.cc: signals, standard streams, failures, memory.
extern "C" void on_stop_signal(int sig);
void install_signal_handlers();
bool keep_standard_streams_open();
int finish_stdout(int code);
int fail(int code, const std::string& message);
int interrupted();
void check_stop();

// plot.cc: --plot, drawn by the Python package: the PNG's path, or
// cli::Failure naming what went wrong.
std::filesystem::path plot_with_python(const std::filesystem::path& out, const char* what);

}  // namespace sim_loop
