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
#include <system_error>
#include <vector>

#include "command.hpp"
#include "sim_loop.hpp"

extern char** environ;

namespace sim_loop {
namespace {

// One try of `python -m simloop plot WHAT --out OUT`: whether it started,
// its wait status and its stderr (up to 64 KiB).
struct Attempt {
  bool started = false;
  int status = 0;
  std::string err;
};

Attempt plot_with(const std::string& python, const char* what, const std::string& out) {
  Attempt attempt;
  const char* argv[] = {python.c_str(), "-m", "simloop", "plot", what, "--out", out.c_str(), nullptr};
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
    return attempt;
  }
  attempt.started = true;
  // Read its stderr until it exits (not until the pipe's end: something it
  // started may hold that open); on a stop, end its process group.
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
      if (n > 0 && attempt.err.size() < (1u << 16)) attempt.err.append(buf, static_cast<size_t>(n));
    }
    const pid_t done = ::waitpid(pid, &attempt.status, WNOHANG);
    exited = done == pid || (done < 0 && errno != EINTR);
  }
  // What it wrote just before exiting, without waiting for the pipe's end.
  ::fcntl(err_pipe[0], F_SETFL, O_NONBLOCK);
  for (char buf[4096]; attempt.err.size() < (1u << 16);) {
    const ssize_t n = ::read(err_pipe[0], buf, sizeof buf);
    if (n <= 0) break;
    attempt.err.append(buf, static_cast<size_t>(n));
  }
  ::close(err_pipe[0]);
  check_stop();
  return attempt;
}

// Its last non-empty line, without our own program's name.
std::string last_line(const std::string& text) {
  const size_t end = text.find_last_not_of(" \r\n");
  if (end == std::string::npos) return "";
  const size_t newline = text.find_last_of('\n', end);
  const size_t begin = newline == std::string::npos ? 0 : newline + 1;
  std::string last = text.substr(begin, end - begin + 1);
  if (last.rfind("sim-loop: ", 0) == 0) last.erase(0, 10);
  return last;
}

bool succeeded(const Attempt& a) { return a.started && WIFEXITED(a.status) && WEXITSTATUS(a.status) == 0; }

// A Python that started but has no simloop package ("python3: No module named simloop").
bool lacks_simloop(const Attempt& a) {
  return a.started && WIFEXITED(a.status) && WEXITSTATUS(a.status) == 1 &&
         last_line(a.err).find("No module named simloop") != std::string::npos;
}

// The Pythons to try, found now: python3 on PATH, then the project's venvs
// beside the folder this sim_loop was built in (scripts/setup.sh makes them).
std::vector<std::string> candidates() {
  std::vector<std::string> found = {"python3"};
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    for (const char* venv : {".venv", ".venv-pypi"}) {
      const std::filesystem::path python = exe.parent_path().parent_path() / venv / "bin" / "python";
      if (std::filesystem::exists(python, error)) found.push_back(python.string());
    }
  }
  return found;
}

[[noreturn]] void plot_failed(const std::string& python, const Attempt& a) {
  const std::string last = last_line(a.err);
  throw simloop::cli::Failure(simloop::cli::kExitRunFailed,
                              "--plot: " + python + " -m simloop plot failed" + (last.empty() ? "" : ": " + last) +
                                  " (the outputs above were written; the plot needs the simloop package and "
                                  "matplotlib; scripts/test.sh installs both into the project's .venv)");
}

}  // namespace

// --plot: the chart is drawn by the Python package (matplotlib), which reads
// the CSV just written, in a child process. The interpreter: $SIMLOOP_PYTHON
// if set; else the first, found at run time, that has the simloop package
// (candidates()).
std::filesystem::path plot_with_python(const std::filesystem::path& out, const char* what) {
  const std::string out_text = out.string();
  const std::filesystem::path png = out / (std::string(what) + ".png");
  const char* env = std::getenv("SIMLOOP_PYTHON");
  if (env && *env) {
    const Attempt a = plot_with(env, what, out_text);
    if (!a.started) {
      throw simloop::cli::Failure(simloop::cli::kExitRunFailed,
                                  std::string("--plot: cannot start ") + env +
                                      " (scripts/test.sh installs the simloop package "
                                      "into the project's .venv; or set SIMLOOP_PYTHON to a Python that has it)");
    }
    if (!succeeded(a)) plot_failed(env, a);
    return png;
  }
  std::string tried;
  for (const std::string& python : candidates()) {
    const Attempt a = plot_with(python, what, out_text);
    if (succeeded(a)) return png;
    if (a.started && !lacks_simloop(a)) plot_failed(python, a);
    tried += (tried.empty() ? "" : ", ") + python;
  }
  throw simloop::cli::Failure(simloop::cli::kExitRunFailed,
                              "--plot: no Python with the simloop package was found (tried " + tried +
                                  "; the outputs above were written): install it with scripts/setup.sh --package "
                                  "(or pip install . in a venv), or set SIMLOOP_PYTHON to a Python that has it");
}

}  // namespace sim_loop
