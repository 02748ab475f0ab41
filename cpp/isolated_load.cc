#include "isolated_load.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>

#include "mujoco_guard.hpp"
#include "simloop/errors.hpp"

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
    mujoco_call([&] { m = mj_loadXML(filename, vfs, error, sizeof error); });
  } catch (const MujocoError& e) {
    reset_mujoco_thread_handlers();
    for (std::string& w : capture.take()) warnings.push_back(one_line(w));
    throw MujocoError(std::string(source) + ": loading the model: " + e.what());
  }
  for (std::string& w : capture.take()) warnings.push_back(one_line(w));
  if (m == nullptr) {
    throw MujocoError(std::string(source) + ": " +
                      (error[0] ? one_line(error) : "MuJoCo could not load the model"));
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
      mujoco_call([&] { size = mj_sizeModel(m); });
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

struct VfsDeleter {
  void operator()(mjVFS* v) const noexcept {
    mj_deleteVFS(v);
    delete v;
  }
};

}  // namespace

mjModel* load_xml_here(const char* filename, const mjVFS* vfs, std::string_view source,
                       std::vector<std::string>& warnings) {
  install_mujoco_handlers();
  const std::lock_guard<std::mutex> lock(load_mutex());
  return load_unlocked(filename, vfs, source, warnings);
}

mjModel* load_xml_in_child(const char* filename, const mjVFS* vfs, std::string_view source,
                           std::vector<std::string>& warnings) {
  install_mujoco_handlers();
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) return nullptr;
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
      child(ends[1], parent, filename, vfs, source);
    }
    ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  }
  ::close(ends[1]);
  if (pid < 0) {
    ::close(ends[0]);
    return nullptr;
  }
  // What the child sends, until it closes the pipe.
  std::unique_ptr<mjVFS, VfsDeleter> compiled;
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
        compiled.reset(new mjVFS);
        mj_defaultVFS(compiled.get());
        int status = 0;
        mujoco_call([&] { status = mj_makeEmptyFileVFS(compiled.get(), "model.mjb", static_cast<int>(size)); });
        if (status != 0) throw MujocoError(std::string(source) + ": could not hold the compiled model in memory");
        complete = read_all(ends[0], compiled->filedata[compiled->nfile - 1], static_cast<std::size_t>(size));
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
    const std::string how = WIFSIGNALED(status)
                                ? "was killed by signal " + std::to_string(WTERMSIG(status)) +
                                      (WTERMSIG(status) == SIGKILL ? " (out of memory?)" : "")
                                : "ended early (exit " + std::to_string(WEXITSTATUS(status)) + ")";
    throw MujocoError(std::string(source) + ": loading the model: the process compiling it " + how);
  }
  if (!error.empty() || !compiled) {
    throw MujocoError(error.empty() ? std::string(source) + ": loading the model failed" : error);
  }
  mjModel* m = nullptr;
  const mjVFS* files = compiled.get();
  try {
    mujoco_call([&] { m = mj_loadModel("model.mjb", files); });
  } catch (const MujocoError& e) {
    throw MujocoError(std::string(source) + ": loading the model: " + e.what());
  }
  if (m == nullptr) throw MujocoError(std::string(source) + ": the compiled model did not load back (mj_loadModel)");
  return m;
}

}  // namespace simloop::detail
