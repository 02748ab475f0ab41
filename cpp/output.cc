#include "simloop/output.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <system_error>
#include <vector>

#include "json_text.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/signals.hpp"

namespace simloop {
namespace {

[[noreturn]] void throw_io(const std::filesystem::path& path, std::string_view what, int err) {
  throw IoError(path.string() + ": " + std::string(what) + " (" + std::strerror(err) + ")");
}

// The header line of trajectory.csv.
void append_csv_header(std::string& out, const std::vector<Column>& columns) {
  for (size_t c = 0; c < columns.size(); ++c) {
    if (c > 0) out += ',';
    out += columns[c].name;
  }
  out += '\n';
}

// `count` rows of trajectory.csv, each columns.size() adjacent values. A row
// is written in a buffer of its own, then appended whole.
void append_csv_rows(std::string& out, const double* rows, std::int64_t count, const std::vector<Column>& columns) {
  const size_t width = columns.size();
  // A cell: a comma and at most kMaxShortestChars (an integer column's
  // int64 fits too); the last one's write_shortest wants kShortestRoom.
  std::vector<char> line(width * (kMaxShortestChars + 1) + kShortestRoom + 1);
  for (std::int64_t r = 0; r < count; ++r) {
    const double* row = rows + static_cast<size_t>(r) * width;
    char* end = line.data();
    for (size_t c = 0; c < width; ++c) {
      if (c > 0) *end++ = ',';
      const double v = row[c];
      if (columns[c].input && std::isnan(v)) continue;  // final row: no inputs
      if (columns[c].integer) {
        end = std::to_chars(end, end + kMaxShortestChars, static_cast<std::int64_t>(v)).ptr;
      } else {
        end = write_shortest(end, v);
      }
    }
    *end++ = '\n';
    out.append(line.data(), end);
  }
}

// TrajectoryCsvSink formats rows in slices of at most about this many bytes.
constexpr size_t kSliceBytes = size_t{1} << 14;

// Blocks the signals that would end the process (or, in the commands, stop
// it) for as long as it lives, in the calling thread.
class BlockTerminatingSignals {
 public:
  BlockTerminatingSignals() {
    sigset_t set;
    sigemptyset(&set);
    for (int sig : kTerminatingSignals) sigaddset(&set, sig);
    blocked_ = ::pthread_sigmask(SIG_BLOCK, &set, &previous_) == 0;
  }
  ~BlockTerminatingSignals() {
    if (blocked_) ::pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
  }
  BlockTerminatingSignals(const BlockTerminatingSignals&) = delete;
  BlockTerminatingSignals& operator=(const BlockTerminatingSignals&) = delete;

 private:
  sigset_t previous_{};
  bool blocked_ = false;
};

}  // namespace

std::string trajectory_csv(const Trajectory& t, const std::vector<Column>& columns) {
  const std::vector<Column> named = columns.empty() ? chapter_columns(t.columns()) : columns;
  if (static_cast<int>(named.size()) != t.columns()) {
    throw InvalidArgument("trajectory.csv: " + std::to_string(t.columns()) + " columns, " +
                          std::to_string(named.size()) + " names");
  }
  std::string out;
  out.reserve(static_cast<size_t>(t.rows() + 1) * static_cast<size_t>(t.columns()) * 12);
  append_csv_header(out, named);
  append_csv_rows(out, t.data(), t.rows(), named);
  return out;
}

void prepare_output_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  if (std::filesystem::is_symlink(dir, ec) && !std::filesystem::exists(dir, ec)) {
    throw IoError(dir.string() + ": a symbolic link to " + std::filesystem::read_symlink(dir, ec).string() +
                  ", which does not exist (make that folder, or give another --out)");
  }
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec)) {
    throw IoError(dir.string() + ": exists and is not a directory");
  }
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(dir.string() + ": cannot create the output directory (" + ec.message() + ")");
  std::string probe = (dir / ".simloop-probe.XXXXXX").string();
  const int fd = ::mkstemp(probe.data());
  if (fd < 0) throw IoError(dir.string() + ": cannot write in the output directory (" + std::strerror(errno) + ")");
  ::close(fd);
  ::unlink(probe.c_str());
}

PendingFile::PendingFile(std::filesystem::path target) : target_(std::move(target)) {
  std::string pattern = (target_.parent_path() / ("." + target_.filename().string() + ".tmp.XXXXXX")).string();
  fd_ = ::mkostemp(pattern.data(), O_CLOEXEC);
  if (fd_ < 0) throw_io(target_, "cannot create a temporary file beside it", errno);
  temp_ = pattern;
}

PendingFile::~PendingFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!temp_.empty()) ::unlink(temp_.c_str());
}

void PendingFile::append(std::string_view bytes) {
  if (fd_ < 0) throw IoError(target_.string() + ": write after finish (a simloop bug)");
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw_io(target_, "cannot write", errno);
    }
    done += static_cast<size_t>(n);
  }
}

void PendingFile::finish() {
  if (fd_ < 0) return;
  const int fd = fd_;
  fd_ = -1;
  // mkstemp makes the file 0600; outputs are ordinary files.
  int err = ::fchmod(fd, 0644) == 0 ? 0 : errno;
  if (::close(fd) != 0 && err == 0) err = errno;
  if (err != 0) throw_io(target_, "cannot write", err);
}

void commit_together(const std::vector<PendingFile*>& files, const RunControl* control) {
  struct Step {
    PendingFile* file;
    std::string backup;  // empty: there was no old file
    bool renamed = false;
  };
  std::vector<Step> steps;
  steps.reserve(files.size());
  for (PendingFile* f : files) {
    if (f->temp_.empty() || f->fd_ >= 0) {
      throw IoError(f->target_.string() + ": commit before finish (a simloop bug)");
    }
    steps.push_back({f, {}, false});
  }
  const BlockTerminatingSignals blocked;
  if (control && control->stop_requested()) throw Interrupted("interrupted");
  // Undoes what was done so far; best effort, it is already a failure path.
  const auto roll_back = [&steps] {
    for (auto s = steps.rbegin(); s != steps.rend(); ++s) {
      const char* target = s->file->target_.c_str();
      if (s->renamed) {
        if (s->backup.empty()) {
          ::unlink(target);
        } else if (::rename(s->backup.c_str(), target) == 0) {
          s->backup.clear();
        }
      }
      if (!s->backup.empty()) {
        // Never renamed: the backup is a second link to the untouched old
        // file, or (moved aside) the old file itself, to be put back.
        struct stat st {};
        if (::lstat(target, &st) != 0) {
          ::rename(s->backup.c_str(), target);
        } else {
          ::unlink(s->backup.c_str());
        }
      }
    }
  };
  // 1. Keep every old file under a second name.
  for (Step& s : steps) {
    const std::filesystem::path& target = s.file->target_;
    struct stat st {};
    if (::lstat(target.c_str(), &st) != 0) {
      if (errno == ENOENT) continue;
      const int err = errno;
      roll_back();
      throw_io(target, "cannot replace", err);
    }
    if (S_ISDIR(st.st_mode)) {
      roll_back();
      throw IoError(target.string() + ": cannot replace (is a directory)");
    }
    std::string backup = s.file->temp_ + ".old";
    if (::link(target.c_str(), backup.c_str()) != 0) {
      const int link_err = errno;
      // No hard links here (some filesystems): move the old file aside. An
      // immutable file refuses both.
      if (::rename(target.c_str(), backup.c_str()) != 0) {
        roll_back();
        throw_io(target, "cannot replace", link_err);
      }
    }
    s.backup = std::move(backup);
  }
  // 2. The new files in.
  for (Step& s : steps) {
    if (::rename(s.file->temp_.c_str(), s.file->target_.c_str()) != 0) {
      const int err = errno;
      roll_back();
      throw_io(s.file->target_, "cannot replace", err);
    }
    s.renamed = true;
    s.file->temp_.clear();
  }
  // 3. The old files out.
  for (Step& s : steps) {
    if (!s.backup.empty()) ::unlink(s.backup.c_str());
  }
}

void write_file_atomically(const std::filesystem::path& path, std::string_view contents) {
  PendingFile file(path);
  file.append(contents);
  file.finish();
  commit_together({&file});
}

void TrajectoryCsvSink::start(int columns, std::int64_t /*rows*/) {
  if (columns_.empty()) columns_ = chapter_columns(columns);
  if (static_cast<int>(columns_.size()) != columns) {
    throw InvalidArgument("trajectory.csv: the run records " + std::to_string(columns) +
                          " columns, the writer was given " + std::to_string(columns_.size()) + " names");
  }
  buffer_.clear();
  buffer_.reserve(kFlushBytes + kSliceBytes);
  append_csv_header(buffer_, columns_);
}

void TrajectoryCsvSink::write(const double* rows, std::int64_t count) {
  // Formatted in slices of at most about kSliceBytes (a cell is a comma and
  // at most kMaxShortestChars), written out once the buffer holds
  // kFlushBytes: the buffer stays within its reserve however many rows come
  // at once. A small buffer, reused: its pages are touched once.
  const auto row_bytes = static_cast<std::int64_t>(columns_.size() * (kMaxShortestChars + 1) + 1);
  const std::int64_t rows_per_slice = std::max<std::int64_t>(1, static_cast<std::int64_t>(kSliceBytes) / row_bytes);
  while (count > 0) {
    const std::int64_t n = std::min(count, rows_per_slice);
    append_csv_rows(buffer_, rows, n, columns_);
    rows += static_cast<size_t>(n) * columns_.size();
    count -= n;
    if (buffer_.size() >= kFlushBytes) {
      file_.append(buffer_);
      buffer_.clear();
    }
  }
}

void TrajectoryCsvSink::finish() {
  file_.append(buffer_);
  buffer_.clear();
  buffer_.shrink_to_fit();
  file_.finish();
}

namespace {
OutputFiles prepared(const std::filesystem::path& dir) {
  prepare_output_dir(dir);
  return {dir / "metrics.json", dir / "trajectory.csv"};
}
}  // namespace

OutputWriter::OutputWriter(const std::filesystem::path& dir, std::vector<Column> columns)
    : files_(prepared(dir)),
      lock_(dir),
      trajectory_file_(files_.trajectory),
      csv_(trajectory_file_, std::move(columns)) {}

OutputFiles OutputWriter::commit(const Metrics& metrics, const RunControl* control,
                                 const std::vector<PendingFile*>& also) {
  return commit(metrics_json(metrics), control, also);
}

OutputFiles OutputWriter::commit(std::string_view metrics_text, const RunControl* control,
                                 const std::vector<PendingFile*>& also) {
  csv_.finish();
  PendingFile metrics_file(files_.metrics);
  metrics_file.append(metrics_text);
  metrics_file.finish();
  std::vector<PendingFile*> files = {&trajectory_file_, &metrics_file};
  files.insert(files.end(), also.begin(), also.end());
  commit_together(files, control);
  return files_;
}

namespace {
OutputFiles write_record(const RunRecord& r, const std::string& metrics_text, const std::filesystem::path& dir) {
  const Trajectory& t = r.trajectory;
  if (t.rows() != r.rows) {
    throw InvalidArgument("this result's rows went to a RowSink when it ran; there are none to write");
  }
  OutputWriter writer(dir, r.columns);
  writer.trajectory().start(t.columns(), t.rows());
  writer.trajectory().write(t.data(), t.rows());
  return writer.commit(metrics_text);
}
}  // namespace

OutputFiles write_outputs(const RunRecord& record, const std::filesystem::path& dir) {
  return write_record(record, metrics_json(record), dir);
}

OutputFiles write_outputs(const RunResult& result, const std::filesystem::path& dir) {
  return write_record(result, metrics_json(result.metrics), dir);
}

}  // namespace simloop
