// A run's rows kept for its drawing (python -m simloop's recording and
// video, drawn once the run is done): blocks of doubles in a file in --out
// that has no name (unlinked at once, so that nothing is left behind however
// the process ends), read back block by block as they were written. Memory
// stays bounded however long the run.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "simloop/rows.hpp"

namespace simloop::cli {

class SpooledRows final : public RowSink {
 public:
  // A file in `dir`; IoError naming it if it cannot be made.
  explicit SpooledRows(const std::filesystem::path& dir);
  SpooledRows(const SpooledRows&) = delete;
  SpooledRows& operator=(const SpooledRows&) = delete;
  ~SpooledRows() override;

  void describe(const std::vector<Column>& columns) override;
  void start(int columns, std::int64_t rows) override;
  void write(const double* rows, std::int64_t count) override;

  [[nodiscard]] const std::vector<std::string>& names() const noexcept { return names_; }
  [[nodiscard]] int columns() const noexcept { return columns_; }
  // The next block as written (its rows, each columns() doubles), from the
  // first; false after the last.
  bool next(std::vector<double>& block);

 private:
  void write_bytes(const void* data, std::size_t size);
  std::string name_;  // for errors: the folder and what the file is
  int fd_ = -1;
  bool reading_ = false;
  int columns_ = 0;
  std::vector<std::string> names_;
};

}  // namespace simloop::cli
