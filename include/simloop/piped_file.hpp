// A file that another library writes as if to a path of its own, while
// simloop does the writing: the recording (rerun's file sink) goes through
// one, so that its bytes are written and checked like the other outputs and
// put in place together with them.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "simloop/output.hpp"

namespace simloop {

// The other side opens writer_path() ("/dev/fd/N": the write end of a pipe)
// and writes to it; a thread of this object reads the pipe and appends every
// byte to a PendingFile beside `target` (".<name>.tmp.XXXXXX"), each write
// checked. A write that fails (a full disk, a file-size limit) is kept for
// finish() to throw, and the thread goes on draining the pipe, discarding,
// so the other side never blocks or fails on its own and the bytes it had
// not written are never half put in place. Nothing here can hang: waiting
// for the end of the stream takes a timeout, and destroying the object stops
// the thread whether or not the other side closed its end.
class PipedFile {
 public:
  explicit PipedFile(std::filesystem::path target);
  PipedFile(const PipedFile&) = delete;
  PipedFile& operator=(const PipedFile&) = delete;
  // Removes the temporary file unless it was committed (see above).
  ~PipedFile();

  [[nodiscard]] const std::string& writer_path() const noexcept { return writer_path_; }
  // Closes this process's copy of the write end, once the other side has
  // opened writer_path(): from then on the stream ends when the other side
  // closes its own.
  void close_writer() noexcept;
  // Waits up to `timeout` for the end of the stream; true once it came.
  [[nodiscard]] bool wait_for_end(std::chrono::milliseconds timeout);
  // Bytes written to the temporary file so far.
  [[nodiscard]] std::int64_t bytes_written() const noexcept;
  // After the end of the stream: throws IoError naming the target if a write
  // failed (the temporary file goes with the object), else makes the file
  // ready for commit_together. Throws IoError if the stream has not ended.
  void finish();
  [[nodiscard]] PendingFile& pending() noexcept { return file_; }
  [[nodiscard]] const std::filesystem::path& target() const noexcept { return file_.target(); }

  struct Stream;  // what the thread shares with this object (and may outlive it with)

 private:
  PendingFile file_;
  std::shared_ptr<Stream> stream_;
  std::string writer_path_;
  std::thread thread_;
};

}  // namespace simloop
