#include "spooled_rows.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "simloop/errors.hpp"

namespace simloop::cli {
namespace {

[[noreturn]] void fail(const std::string& name, const char* doing, int err) {
  throw IoError(name + ": " + doing + " (" + std::strerror(err) + ")");
}

}  // namespace

SpooledRows::SpooledRows(const std::filesystem::path& dir)
    : name_((dir / ".sim_loop.rows").string() + " (the run's rows, kept for its drawing)") {
  fd_ = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd_ < 0) {  // a file system without O_TMPFILE: a named file, unlinked at once
    std::string path = (dir / ".sim_loop.rows.XXXXXX").string();
    fd_ = ::mkostemp(path.data(), O_CLOEXEC);
    if (fd_ < 0) fail(name_, "cannot create", errno);
    ::unlink(path.c_str());
  }
}

SpooledRows::~SpooledRows() {
  if (fd_ >= 0) ::close(fd_);
}

void SpooledRows::describe(const std::vector<Column>& columns) {
  names_.clear();
  for (const Column& c : columns) names_.push_back(c.name);
}

void SpooledRows::start(int columns, std::int64_t /*rows*/) { columns_ = columns; }

void SpooledRows::write_bytes(const void* data, std::size_t size) {
  const char* bytes = static_cast<const char*>(data);
  for (std::size_t done = 0; done < size;) {
    const ssize_t n = ::write(fd_, bytes + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail(name_, "cannot write", errno);
    done += static_cast<std::size_t>(n);
  }
}

void SpooledRows::write(const double* rows, std::int64_t count) {
  if (count <= 0) return;
  write_bytes(&count, sizeof count);
  write_bytes(rows, static_cast<std::size_t>(count) * static_cast<std::size_t>(columns_) * sizeof(double));
}

bool SpooledRows::next(std::vector<double>& block) {
  if (!reading_) {
    if (::lseek(fd_, 0, SEEK_SET) < 0) fail(name_, "cannot read", errno);
    reading_ = true;
  }
  const auto read_bytes = [&](void* data, std::size_t size) {
    char* bytes = static_cast<char*>(data);
    std::size_t done = 0;
    while (done < size) {
      const ssize_t n = ::read(fd_, bytes + done, size - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) fail(name_, "cannot read", errno);
      if (n == 0) break;
      done += static_cast<std::size_t>(n);
    }
    return done;
  };
  std::int64_t count = 0;
  const std::size_t got = read_bytes(&count, sizeof count);
  if (got == 0) return false;
  const std::size_t size = static_cast<std::size_t>(count) * static_cast<std::size_t>(columns_);
  block.resize(size);
  if (got != sizeof count || read_bytes(block.data(), size * sizeof(double)) != size * sizeof(double)) {
    fail(name_, "cannot read", EIO);
  }
  return true;
}

}  // namespace simloop::cli
