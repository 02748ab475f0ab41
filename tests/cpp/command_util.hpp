// Running sim_loop as a user does, for the command's tests: a real process
// in a scratch directory (or in the background, to be signalled), and its
// outputs read back.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "test_util.hpp"

extern char** environ;

namespace test {

namespace fs = std::filesystem;

struct Outcome {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs sim_loop with `args` in `cwd`, with stdin closed and a time limit so a
// hang (MuJoCo waiting for Enter, say) fails the test instead of blocking it.
// `shell_prefix` runs first in the same shell (a ulimit, say); `stdout_to`
// replaces the redirection of stdout (then o.out stays empty).
inline Outcome sim_loop(const fs::path& cwd, const std::vector<std::string>& args, const std::string& shell_prefix = "",
                        const std::string& stdout_to = "") {
  const fs::path out = cwd / ".stdout", err = cwd / ".stderr";
  std::string cmd =
      "cd " + shell_quote(cwd.string()) + " && " + shell_prefix + " timeout 60 " + shell_quote(SIM_LOOP_EXE);
  for (const auto& a : args) cmd += " " + shell_quote(a);
  cmd += " < /dev/null " + (stdout_to.empty() ? "> " + shell_quote(out.string()) : stdout_to) + " 2> " +
         shell_quote(err.string());
  const int status = std::system(cmd.c_str());
  Outcome o;
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  o.out = test::read_text(out);
  o.err = test::read_text(err);
  fs::remove(out);
  fs::remove(err);
  return o;
}

inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Column name -> values, from a trajectory.csv.
inline std::map<std::string, std::vector<double>> read_csv(const fs::path& path) {
  const auto lines = lines_of(test::read_text(path));
  std::vector<std::string> names;
  std::istringstream header(lines.at(0));
  for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  std::map<std::string, std::vector<double>> columns;
  for (size_t i = 1; i < lines.size(); ++i) {
    std::istringstream row(lines[i]);
    std::string cell;
    for (const auto& name : names) {
      std::getline(row, cell, ',');
      columns[name].push_back(cell.empty() ? std::nan("") : std::strtod(cell.c_str(), nullptr));
    }
  }
  return columns;
}

// Every file under `dir` with its bytes and modification time.
inline std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    struct stat st {};
    ::stat(e.path().c_str(), &st);
    files[e.path().string()] =
        test::read_text(e.path()) + "@" + std::to_string(st.st_mtim.tv_sec) + "." + std::to_string(st.st_mtim.tv_nsec);
  }
  return files;
}

// sim_loop started in the background, so that a test can signal it.
class Background {
 public:
  Background(const fs::path& cwd, const std::vector<std::string>& args) : cwd_(cwd) {
    std::vector<std::string> argv_text = {SIM_LOOP_EXE};
    argv_text.insert(argv_text.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_text) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addchdir_np(&actions, cwd.c_str());
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 1, ".stdout", O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, ".stderr", O_WRONLY | O_CREAT | O_TRUNC, 0644);
    // As a terminal's shell starts it: SIGINT and SIGTERM not ignored, even
    // if this test runs as a background job (which ignores SIGINT).
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    sigset_t defaults;
    sigemptyset(&defaults);
    sigaddset(&defaults, SIGINT);
    sigaddset(&defaults, SIGTERM);
    posix_spawnattr_setsigdefault(&attributes, &defaults);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF);
    if (posix_spawn(&pid_, SIM_LOOP_EXE, &actions, &attributes, argv.data(), environ) != 0) pid_ = -1;
    posix_spawnattr_destroy(&attributes);
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Background() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Background(const Background&) = delete;
  Background& operator=(const Background&) = delete;

  [[nodiscard]] bool started() const { return pid_ > 0; }
  // Once it has printed its banner (its signal handlers are in place by
  // then) and `delay` more has passed, sends `sig` and waits up to 10 s for
  // the process to end: its stdout, stderr and exit code (-1 if a signal
  // killed it, -2 if it was still running, and then killed), and in
  // `seconds` how long it took from the signal.
  Outcome signal_after(std::chrono::duration<double> delay, int sig, double* seconds) {
    const auto limit = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (test::read_text(cwd_ / ".stdout").empty() && std::chrono::steady_clock::now() < limit) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    std::this_thread::sleep_for(delay);
    ::kill(pid_, sig);
    Outcome o;
    wait(std::chrono::seconds(10), seconds, &o);
    return o;
  }

 private:
  void wait(std::chrono::duration<double> limit, double* seconds, Outcome* o) {
    const auto start = std::chrono::steady_clock::now();
    int status = 0;
    int code = -2;
    for (;;) {
      const pid_t done = ::waitpid(pid_, &status, WNOHANG);
      if (done == pid_) {
        code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        pid_ = -1;
        break;
      }
      if (std::chrono::steady_clock::now() - start > limit) break;
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
    *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
      pid_ = -1;
    }
    o->exit_code = code;
    o->out = test::read_text(cwd_ / ".stdout");
    o->err = test::read_text(cwd_ / ".stderr");
    fs::remove(cwd_ / ".stdout");
    fs::remove(cwd_ / ".stderr");
  }

  fs::path cwd_;
  pid_t pid_ = -1;
};

// The names in `dir`, sorted.
inline std::set<std::string> names_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

}  // namespace test
