#include "isolated_load.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>

#include "mujoco_compat.hpp"
#include "mujoco_guard.hpp"
#include "simloop/errors.hpp"
#include "simloop/rows.hpp"

namespace simloop::detail {
namespace {

// Held around every mj_loadXML of this library and across the fork, so that
// no thread of ours is inside MuJoCo's loader (which holds a mutex of its
// own) when the child is made: the child's copy of that mutex is free.
std::mutex& load_mutex() {
  static std::mutex mutex;
  return mutex;
}

mjModel* load_unlocked(const char* filename, const mjVFS* vfs, std::string_view source,
                       std::vector<std::string>& warnings) {
  char error[1024] = "";
  mjModel* m = nullptr;
  CaptureWarnings capture;
  try {
    mujoco_call([&] { m = compat::load_xml(filename, vfs, error, sizeof error); });
  } catch (const MujocoError& e) {
    reset_mujoco_thread_handlers();
    for (std::string& w : capture.take()) warnings.push_back(one_line(w));
    throw MujocoError(std::string(source) + ": loading the model: " + e.what());
  }
  for (std::string& w : capture.take()) warnings.push_back(one_line(w));
  if (m == nullptr) {
    throw MujocoError(std::string(source) + ": " + (error[0] ? one_line(error) : "MuJoCo could not load the model"));
  }
  if (error[0]) warnings.push_back(one_line(error));  // a compiled model: the compiler's warning
  return m;
}

// Records on the pipe: a kind byte, a 64-bit length, then the bytes.
constexpr char kWarning = 'W', kError = 'E', kModel = 'M';

bool write_all(int fd, const void* data, std::size_t size) {
  const char* at = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, at, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    at += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

bool send(int fd, char kind, std::string_view bytes) {
  const std::uint64_t size = bytes.size();
  return write_all(fd, &kind, 1) && write_all(fd, &size, sizeof size) && write_all(fd, bytes.data(), bytes.size());
}

bool read_all(int fd, void* data, std::size_t size) {
  char* at = static_cast<char*>(data);
  while (size > 0) {
    const ssize_t n = ::read(fd, at, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    at += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

// The child's memory: its data now (the parent's, copied) and the budget a
// run's trajectories get. Past it MuJoCo's allocations fail and the load ends
// in one line, where a 100000 x 100000 height field would grow until the
// kernel's OOM killer ended it (and maybe others).
void limit_memory(std::uint64_t budget) {
  std::FILE* statm = std::fopen("/proc/self/statm", "r");
  unsigned long long pages[6] = {};
  const bool read = statm != nullptr && std::fscanf(statm, "%llu %llu %llu %llu %llu %llu", &pages[0], &pages[1],
                                                    &pages[2], &pages[3], &pages[4], &pages[5]) == 6;
  if (statm != nullptr) std::fclose(statm);
  if (!read) return;
  const std::uint64_t data = pages[5] * static_cast<std::uint64_t>(::sysconf(_SC_PAGE_SIZE));  // data + stack
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_DATA, &limit) != 0) return;
  const std::uint64_t wanted = data + budget;
  if (limit.rlim_cur == RLIM_INFINITY || wanted < limit.rlim_cur) {
    limit.rlim_cur = static_cast<rlim_t>(wanted);
    ::setrlimit(RLIMIT_DATA, &limit);
  }
}

// The child: compile, send, exit. Never returns.
[[noreturn]] void child(int out, pid_t parent, const char* filename, const mjVFS* vfs, std::string_view source) {
  // Signals: the default action for each (not the parent's handlers, which
  // would report a stop as the command), but the ones a terminal sends its
  // whole process group, which the parent acts on; the child goes when the
  // parent does.
  for (int sig = 1; sig < NSIG; ++sig) {
    struct sigaction current {};
    if (sig == SIGKILL || sig == SIGSTOP || ::sigaction(sig, nullptr, &current) != 0) continue;
    if (current.sa_handler == SIG_IGN) continue;
    struct sigaction action {};
    action.sa_handler = sig == SIGINT || sig == SIGQUIT || sig == SIGHUP ? SIG_IGN : SIG_DFL;
    sigemptyset(&action.sa_mask);
    ::sigaction(sig, &action, nullptr);
  }
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) ::_exit(1);
  limit_memory(trajectory_memory_budget());
  sigset_t none;
  sigemptyset(&none);
  ::pthread_sigmask(SIG_SETMASK, &none, nullptr);

  std::vector<std::string> warnings;
  std::string failure;
  mjModel* m = nullptr;
  try {
    m = load_unlocked(filename, vfs, source, warnings);
  } catch (const std::bad_alloc&) {
    failure = std::string(source) + ": loading the model: MuJoCo ran out of memory";
  } catch (const std::exception& e) {
    failure = e.what();
  }
  for (const std::string& w : warnings) {
    if (!send(out, kWarning, w)) ::_exit(1);
  }
  if (m != nullptr) {
    try {
      int size = 0;
      mujoco_call([&] { size = compat::as_int(mj_sizeModel(m)); });
      std::string bytes(static_cast<std::size_t>(size), '\0');
      char* buffer = bytes.data();
      mujoco_call([&] { mj_saveModel(m, nullptr, buffer, size); });
      ::_exit(send(out, kModel, bytes) ? 0 : 1);
    } catch (const std::bad_alloc&) {
      failure = std::string(source) + ": loading the model: out of memory while handing the compiled model back";
    } catch (const std::exception& e) {
      failure = std::string(source) + ": handing the compiled model back: " + e.what();
    }
  }
  ::_exit(send(out, kError, failure) ? 0 : 1);
}

struct FdCloser {
  int fd;
  ~FdCloser() {
    if (fd >= 0) ::close(fd);
  }
};

// The last non-empty line of what was written to `fd` (at most its last 4 KiB).
std::string last_line(int fd) {
  if (fd < 0) return {};
  const off_t end = ::lseek(fd, 0, SEEK_END);
  if (end <= 0) return {};
  const off_t from = std::max<off_t>(0, end - 4096);
  std::string text(static_cast<std::size_t>(end - from), '\0');
  const ssize_t n = ::pread(fd, text.data(), text.size(), from);
  text.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) text.pop_back();
  const std::size_t newline = text.find_last_of('\n');
  return newline == std::string::npos ? text : text.substr(newline + 1);
}

}  // namespace

mjModel* load_xml_here(const char* filename, const mjVFS* vfs, std::string_view source,
                       std::vector<std::string>& warnings) {
  install_mujoco_handlers(/*plugins=*/false);
  const std::lock_guard<std::mutex> lock(load_mutex());
  return load_unlocked(filename, vfs, source, warnings);
}

mjModel* load_xml_in_child(const char* filename, const mjVFS* vfs, std::string_view source,
                           std::vector<std::string>& warnings) {
  install_mujoco_handlers();
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) return nullptr;
  // The child's stderr, read only if it dies: what a library that ends the
  // process says on the way out (MuJoCo 4's libc++ names an uncaught
  // std::bad_alloc there) goes into the error, not onto the user's terminal.
  const int child_stderr = ::memfd_create("simloop-compile-stderr", MFD_CLOEXEC);
  pid_t pid = -1;
  {
    const std::lock_guard<std::mutex> lock(load_mutex());
    // No signal handler may run in the child before it has put them back.
    sigset_t all, previous;
    sigfillset(&all);
    ::pthread_sigmask(SIG_BLOCK, &all, &previous);
    const pid_t parent = ::getpid();
    pid = ::fork();
    if (pid == 0) {
      ::close(ends[0]);
      if (child_stderr >= 0) ::dup2(child_stderr, STDERR_FILENO);
      child(ends[1], parent, filename, vfs, source);
    }
    ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  }
  ::close(ends[1]);
  const FdCloser close_stderr{child_stderr};
  if (pid < 0) {
    ::close(ends[0]);
    return nullptr;
  }
  // What the child sends, until it closes the pipe.
  std::string compiled;
  std::string error;
  std::vector<std::string> sent_warnings;
  bool complete = false;
  try {
    for (;;) {
      char kind = 0;
      std::uint64_t size = 0;
      if (!read_all(ends[0], &kind, 1) || !read_all(ends[0], &size, sizeof size)) break;
      if (kind == kModel) {
        if (size == 0 || size > static_cast<std::uint64_t>(INT_MAX)) break;
        compiled.resize(static_cast<std::size_t>(size));
        complete = read_all(ends[0], compiled.data(), compiled.size());
        break;
      }
      std::string text(static_cast<std::size_t>(std::min<std::uint64_t>(size, 1u << 20)), '\0');
      if (size != text.size() || !read_all(ends[0], text.data(), text.size())) break;
      if (kind == kWarning) sent_warnings.push_back(std::move(text));
      if (kind == kError) {
        error = std::move(text);
        complete = true;
        break;
      }
    }
  } catch (...) {
    ::close(ends[0]);
    ::kill(pid, SIGKILL);
    while (::waitpid(pid, nullptr, 0) < 0 && errno == EINTR) {
    }
    throw;
  }
  ::close(ends[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  warnings.insert(warnings.end(), sent_warnings.begin(), sent_warnings.end());
  if (!complete) {
    const std::string said = last_line(child_stderr);
    if (said.find("bad_alloc") != std::string::npos) {
      throw MujocoError(std::string(source) + ": loading the model: MuJoCo ran out of memory (" + said + ")");
    }
    // MuJoCo 4's compiler does not check every allocation: past the child's
    // memory budget it can crash where 2.2's said "Could not allocate memory".
    const int signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
    const std::string crashed =
        signal == SIGSEGV || signal == SIGBUS || signal == SIGABRT
            ? "; out of memory? a compile may use " + std::to_string(trajectory_memory_budget() >> 20) + " MiB"
            : "";
    const std::string how = signal != 0
                                ? "was killed by signal " + std::to_string(signal) + " (" + ::strsignal(signal) +
                                      (signal == SIGKILL ? "; out of memory?)" : crashed + ")")
                                : "ended early (exit " + std::to_string(WEXITSTATUS(status)) + ")";
    throw MujocoError(std::string(source) + ": loading the model: the process compiling it " + how +
                      (said.empty() ? "" : ": " + said));
  }
  if (!error.empty() || compiled.empty()) {
    throw MujocoError(error.empty() ? std::string(source) + ": loading the model failed" : error);
  }
  mjModel* m = nullptr;
  const compat::OneFileVfs vfs_back("model.mjb", compiled, source, "compiled model");
  const mjVFS* files = vfs_back.get();
  try {
    mujoco_call([&] { m = mj_loadModel("model.mjb", files); });
  } catch (const MujocoError& e) {
    throw MujocoError(std::string(source) + ": loading the model: " + e.what());
  }
  if (m == nullptr) throw MujocoError(std::string(source) + ": the compiled model did not load back (mj_loadModel)");
  return m;
}

}  // namespace simloop::detail
