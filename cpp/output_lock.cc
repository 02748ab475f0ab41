#include "simloop/output_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <system_error>
#include <utility>

namespace simloop {

struct OutputLock::Held {
  std::pair<dev_t, ino_t> key{};
  int fd = -1;
  pid_t pid = 0;  // the process that took it (a forked child is another run)
  Held() = default;
  Held(const Held&) = delete;
  Held& operator=(const Held&) = delete;
  ~Held();
};

namespace {

// The folders this process holds, so that a second lock on one shares the
// first (not in a forked child, which is a run of its own: it inherits this
// map but not the right to the lock). Guarded by g_mutex, under which a lock is also taken and released,
// so two threads never race to flock the same folder. Never destroyed: a
// lock may be released during the process's exit.
std::mutex g_mutex;
std::map<std::pair<dev_t, ino_t>, std::weak_ptr<OutputLock::Held>>& registry() {
  static auto* held = new std::map<std::pair<dev_t, ino_t>, std::weak_ptr<OutputLock::Held>>();
  return *held;
}

std::string error_text(int err) { return std::strerror(err); }

}  // namespace

OutputLock::Held::~Held() {
  const std::lock_guard<std::mutex> lock(g_mutex);
  if (fd >= 0) ::close(fd);  // releases the flock
  const auto it = registry().find(key);
  if (it != registry().end() && it->second.expired()) registry().erase(it);
}

long detail::flock_holder(unsigned long long device, unsigned long long inode) {
  std::FILE* locks = std::fopen("/proc/locks", "re");
  if (locks == nullptr) return 0;
  char wanted[96];
  std::snprintf(wanted, sizeof wanted, "%02x:%02x:%llu", major(static_cast<dev_t>(device)),
                minor(static_cast<dev_t>(device)), inode);
  long holder = 0;
  char line[512];
  while (holder == 0 && std::fgets(line, sizeof line, locks) != nullptr) {
    // "1: FLOCK  ADVISORY  WRITE 12345 fd:01:1234567 0 EOF"; a waiter's
    // line has "->" after the number and is skipped.
    char id[32], kind[32], mode[32], access[32], where[96];
    long pid = 0;
    if (std::sscanf(line, "%31s %31s %31s %31s %ld %95s", id, kind, mode, access, &pid, where) == 6 &&
        std::strcmp(kind, "FLOCK") == 0 && std::strcmp(where, wanted) == 0 && pid > 0) {
      holder = pid;
    }
  }
  std::fclose(locks);
  return holder;
}

OutputLock::OutputLock(const std::filesystem::path& dir) {
  for (int attempt = 0;; ++attempt) {
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) throw IoError(dir.string() + ": cannot open the folder to lock it (" + error_text(errno) + ")");
    struct stat opened {};
    ::fstat(fd, &opened);
    const std::pair<dev_t, ino_t> key{opened.st_dev, opened.st_ino};
    const std::lock_guard<std::mutex> lock(g_mutex);
    const auto it = registry().find(key);
    if (it != registry().end()) {
      std::shared_ptr<Held> held = it->second.lock();
      if (held && held->pid == ::getpid()) {
        ::close(fd);
        held_ = std::move(held);
        return;
      }
    }
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      if (err == EWOULDBLOCK) {
        ::close(fd);
        const long pid = detail::flock_holder(opened.st_dev, opened.st_ino);
        throw OutputInUse(dir.string() + ": another simloop run" +
                          (pid > 0 ? " (pid " + std::to_string(pid) + ")" : std::string()) +
                          " is writing in this folder; wait for it to end, or choose another folder");
      }
      if (err != ENOLCK && err != EOPNOTSUPP && err != EINVAL) {
        ::close(fd);
        throw IoError(dir.string() + ": cannot lock the folder (" + error_text(err) + ")");
      }
      // A file system without locks: run on without one.
    }
    // A run that held the folder may have removed it (it made it, and left
    // nothing in it) between our open and our flock: then the lock is on a
    // folder no path leads to. Make it again and lock that.
    struct stat now {};
    if (::stat(dir.c_str(), &now) != 0 || now.st_dev != opened.st_dev || now.st_ino != opened.st_ino) {
      ::close(fd);
      if (attempt >= 3) throw IoError(dir.string() + ": the folder keeps being removed while it is being locked");
      std::error_code ignored;
      std::filesystem::create_directories(dir, ignored);
      continue;
    }
    auto held = std::make_shared<Held>();
    held->key = key;
    held->fd = fd;
    held->pid = ::getpid();
    registry()[key] = held;
    held_ = std::move(held);
    return;
  }
}

}  // namespace simloop
