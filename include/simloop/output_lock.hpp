// One run at a time in an output folder.
//
// Two runs writing the same folder at once would each put their pair of
// outputs in place, and the renames of the two could interleave: metrics.json
// from one run beside trajectory.csv from the other. A run therefore holds an
// OutputLock on its folder for as long as it may write there; a second run
// is refused at once (OutputInUse, naming the folder and the other process)
// rather than made to wait: it would only overwrite the first run's outputs
// when its turn came, which is not what anyone running two jobs into one
// folder meant.
//
// The lock is flock(2) on the folder itself (opened read-only): advisory,
// released by the kernel when the process ends however it ends (SIGKILL and
// power cuts included), so there is no lock file to leave behind or to go
// stale. Within one process the lock is shared: a second OutputLock on a
// folder this process already holds (the command's lock, then its
// OutputWriter's) just adds a reference.
#pragma once

#include <filesystem>
#include <memory>

#include "simloop/errors.hpp"

namespace simloop {

// Another process holds the folder's lock. The message names the folder and,
// where the system says (/proc/locks), the other process's pid.
class OutputInUse : public IoError {
 public:
  using IoError::IoError;
};

class OutputLock {
 public:
  // Locks `dir`, which must exist (prepare_output_dir makes it). Throws
  // OutputInUse if another process holds it, IoError if it cannot be opened.
  // A file system that has no locks (flock fails with ENOLCK or EOPNOTSUPP)
  // is run on without one.
  explicit OutputLock(const std::filesystem::path& dir);
  OutputLock(const OutputLock&) = default;
  OutputLock& operator=(const OutputLock&) = default;
  OutputLock(OutputLock&&) noexcept = default;
  OutputLock& operator=(OutputLock&&) noexcept = default;
  ~OutputLock() = default;

  struct Held;

 private:
  std::shared_ptr<Held> held_;
};

namespace detail {
// The pid holding a flock on the file (device, inode), from /proc/locks, or
// 0 if it cannot be told.
long flock_holder(unsigned long long device, unsigned long long inode);
}  // namespace detail

}  // namespace simloop
