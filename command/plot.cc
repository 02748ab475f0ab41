// --plot: sim_loop hands the chart to the Python package in a child process,
// and reports its failure (cli::Failure) or a stop (Interrupted) in one line.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "command.hpp"
#include "sim_loop.hpp"

extern char** environ;

namespace sim_loop {

// --plot: the chart is drawn by the Python package (matplotlib), which reads
// the CSV just written. The interpreter: $SIMLOOP_PYTHON if set, else the one
// CMake recorded (the project's .venv, which scripts/test.sh makes).
std::filesystem::path plot_with_python(const std::filesystem::path& out, const char* what) {
  const char* env = std::getenv("SIMLOOP_PYTHON");
  const std::string python = env && *env ? env : SIMLOOP_DEFAULT_PYTHON;
  const std::string out_text = out.string();
  const char* argv[] = {python.c_str(), "-m", "simloop", "plot", what, "--out", out_text.c_str(), nullptr};
  // Its stderr comes back through a pipe: a failure is reported in our one
  // line (its last line, a traceback's verdict), not as a traceback and ours.
  int err_pipe[2];
  if (::pipe2(err_pipe, O_CLOEXEC) != 0) {
    throw simloop::cli::Failure(simloop::cli::kExitRunFailed,
                                "--plot: cannot start " + python + " (" + std::strerror(errno) + ")");
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
    throw simloop::cli::Failure(simloop::cli::kExitRunFailed,
                                "--plot: cannot start " + python +
                                    " (scripts/test.sh installs the simloop package "
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
    throw simloop::cli::Failure(simloop::cli::kExitRunFailed,
                                "--plot: " + python + " -m simloop plot failed" +
                                    (last.empty() ? std::string() : ": " + last) +
                                    " (the outputs above were written; the plot needs the simloop package and "
                                    "matplotlib; scripts/test.sh installs both into the project's .venv)");
  }
  return out / (std::string(what) + ".png");
}

}  // namespace sim_loop
