// The sim_loop process itself: its one RunControl and stop state, the
// terminating signals, its standard streams, its one-line failures and its
// peak memory.
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>

#include "sim_loop.hpp"
#include "simloop/errors.hpp"
#include "simloop/signals.hpp"

namespace sim_loop {

TerminalProgress g_progress;

// The command's one control: a terminating signal requests a stop, the loops
// throw Interrupted within a chunk of steps, and the outputs' temporary files
// go with the stack. Made at startup, on the main thread (its owner). Its
// poll draws the progress bar; without a terminal there is no poll at all,
// so the loop does not even read the clock for it.
simloop::RunControl g_control =
    TerminalProgress::wanted()
        ? simloop::RunControl([](std::int64_t done, std::int64_t total) { g_progress.draw(done, total); })
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

}  // namespace sim_loop
