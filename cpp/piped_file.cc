#include "simloop/piped_file.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/signals.hpp"

namespace simloop {

PipedFile::PipedFile(std::filesystem::path target) : file_(std::move(target)) {
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) {
    throw IoError(file_.target().string() + ": cannot make a pipe to write it through (" + std::strerror(errno) + ")");
  }
  read_fd_ = ends[0];
  write_fd_ = ends[1];
  stop_fd_ = ::eventfd(0, EFD_CLOEXEC);
  if (stop_fd_ < 0) {
    const int err = errno;
    ::close(read_fd_);
    ::close(write_fd_);
    throw IoError(file_.target().string() + ": cannot make an eventfd (" + std::strerror(err) + ")");
  }
  writer_path_ = "/dev/fd/" + std::to_string(write_fd_);
  // The thread takes no signal: they stay for the threads that act on them
  // (a Python interpreter's main thread, say).
  sigset_t all, previous;
  sigfillset(&all);
  ::pthread_sigmask(SIG_BLOCK, &all, &previous);
  try {
    thread_ = std::thread([this] { drain(); });
  } catch (...) {
    ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
    ::close(read_fd_);
    ::close(write_fd_);
    ::close(stop_fd_);
    throw;
  }
  ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
}

PipedFile::~PipedFile() {
  close_writer();
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(stop_fd_, &one, sizeof one);
  if (thread_.joinable()) thread_.join();
  ::close(read_fd_);
  ::close(stop_fd_);
}

void PipedFile::close_writer() noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (write_fd_ >= 0) ::close(write_fd_);
  write_fd_ = -1;
}

void PipedFile::drain() noexcept {
  std::vector<char> buffer(std::size_t{1} << 20);
  for (;;) {
    pollfd fds[2] = {{read_fd_, POLLIN, 0}, {stop_fd_, POLLIN, 0}};
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    if (fds[1].revents != 0) break;  // the destructor: stop at once
    const ssize_t n = ::read(read_fd_, buffer.data(), buffer.size());
    if (n < 0) {
      const int err = errno;
      if (err == EINTR || err == EAGAIN) continue;
      const std::lock_guard<std::mutex> lock(mutex_);
      if (error_.empty()) error_ = file_.target().string() + ": cannot read the pipe (" + std::strerror(err) + ")";
      break;
    }
    if (n == 0) break;  // every write end closed: the stream is complete
    bool failed = false;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      failed = !error_.empty();
    }
    if (failed) continue;  // discard: the file is lost already, keep the writer going
    try {
      file_.append(std::string_view(buffer.data(), static_cast<std::size_t>(n)));
      const std::lock_guard<std::mutex> lock(mutex_);
      written_ += n;
    } catch (const std::exception& e) {
      const std::lock_guard<std::mutex> lock(mutex_);
      error_ = e.what();
    }
  }
  const std::lock_guard<std::mutex> lock(mutex_);
  ended_ = true;
  ended_cv_.notify_all();
}

bool PipedFile::wait_for_end(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  return ended_cv_.wait_for(lock, timeout, [this] { return ended_; });
}

std::int64_t PipedFile::bytes_written() const noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  return written_;
}

void PipedFile::finish() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!ended_) throw IoError(file_.target().string() + ": finished before its writer closed it (a simloop bug)");
  }
  if (thread_.joinable()) thread_.join();
  if (!error_.empty()) throw IoError(error_);
  file_.finish();
}

}  // namespace simloop
