#include "simloop/piped_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <vector>

#include "simloop/errors.hpp"

namespace simloop {

// The pipe and what the thread found. The thread holds a reference, so
// that, left to drain after the PipedFile is gone, it touches only this.
struct PipedFile::Stream {
  int read_fd = -1;
  int write_fd = -1;
  std::mutex mutex;
  std::condition_variable ended_cv;
  bool ended = false;
  PendingFile* file = nullptr;  // null once the PipedFile stopped taking bytes
  std::string error;            // the first failed write's message
  std::int64_t written = 0;
  ~Stream() {
    if (read_fd >= 0) ::close(read_fd);
    if (write_fd >= 0) ::close(write_fd);
  }
};

namespace {

// Reads the pipe to its end, appending to the stream's file while it has one
// and no write failed, discarding otherwise.
void drain(const std::shared_ptr<PipedFile::Stream>& s) noexcept {
  std::vector<char> buffer(std::size_t{1} << 20);
  for (;;) {
    const ssize_t n = ::read(s->read_fd, buffer.data(), buffer.size());
    if (n < 0) {
      const int err = errno;
      if (err == EINTR || err == EAGAIN) continue;
      const std::lock_guard<std::mutex> lock(s->mutex);
      if (s->error.empty() && s->file != nullptr) {
        s->error = s->file->target().string() + ": cannot read the pipe (" + std::strerror(err) + ")";
      }
      break;
    }
    if (n == 0) break;  // every write end closed: the stream is complete
    // Under the lock, so that the PipedFile never lets its file go mid-write.
    const std::lock_guard<std::mutex> lock(s->mutex);
    if (s->file == nullptr || !s->error.empty()) continue;  // discard: keep the writer going
    try {
      s->file->append(std::string_view(buffer.data(), static_cast<std::size_t>(n)));
      s->written += n;
    } catch (const std::exception& e) {
      s->error = e.what();
    }
  }
  const std::lock_guard<std::mutex> lock(s->mutex);
  s->ended = true;
  s->ended_cv.notify_all();
}

}  // namespace

PipedFile::PipedFile(std::filesystem::path target) : file_(std::move(target)), stream_(std::make_shared<Stream>()) {
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) {
    throw IoError(file_.target().string() + ": cannot make a pipe to write it through (" + std::strerror(errno) + ")");
  }
  stream_->read_fd = ends[0];
  stream_->write_fd = ends[1];
  stream_->file = &file_;
  writer_path_ = "/dev/fd/" + std::to_string(ends[1]);
  // The thread takes no signal: they stay for the threads that act on them
  // (a Python interpreter's main thread, say).
  sigset_t all, previous;
  sigfillset(&all);
  ::pthread_sigmask(SIG_BLOCK, &all, &previous);
  try {
    thread_ = std::thread([s = stream_] { drain(s); });
  } catch (...) {
    ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
    throw;
  }
  ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
}

PipedFile::~PipedFile() {
  close_writer();
  bool ended = false;
  {
    const std::lock_guard<std::mutex> lock(stream_->mutex);
    stream_->file = nullptr;  // no more bytes into file_, which goes next
    ended = stream_->ended;
  }
  if (thread_.joinable()) {
    if (ended) {
      thread_.join();
    } else {
      thread_.detach();  // drains and discards until the other side closes its end
    }
  }
}

void PipedFile::close_writer() noexcept {
  const std::lock_guard<std::mutex> lock(stream_->mutex);
  if (stream_->write_fd >= 0) ::close(stream_->write_fd);
  stream_->write_fd = -1;
}

bool PipedFile::wait_for_end(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(stream_->mutex);
  return stream_->ended_cv.wait_for(lock, timeout, [this] { return stream_->ended; });
}

std::int64_t PipedFile::bytes_written() const noexcept {
  const std::lock_guard<std::mutex> lock(stream_->mutex);
  return stream_->written;
}

void PipedFile::finish() {
  std::string error;
  {
    const std::lock_guard<std::mutex> lock(stream_->mutex);
    if (!stream_->ended) {
      throw IoError(file_.target().string() + ": finished before its writer closed it (a simloop bug)");
    }
    error = stream_->error;
  }
  if (thread_.joinable()) thread_.join();
  if (!error.empty()) throw IoError(error);
  file_.finish();
}

}  // namespace simloop
