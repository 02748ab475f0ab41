// Small helpers shared by the C++ tests.
#pragma once

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "simloop/errors.hpp"

namespace test {

// A fresh directory under the system's temp dir, removed with its contents.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "simloop-test.XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) std::abort();
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// What error_of gives when `f` throws nothing.
inline constexpr const char* kNoInvalidArgument = "(no InvalidArgument)";

// The message of the simloop::InvalidArgument that `f` throws (kNoInvalidArgument if none).
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const simloop::InvalidArgument& e) {
    return e.what();
  }
  return kNoInvalidArgument;
}

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Runs `fn` with the working directory set to `dir`, then restores it.
template <class F>
void in_directory(const std::filesystem::path& dir, F&& fn) {
  const auto previous = std::filesystem::current_path();
  std::filesystem::current_path(dir);
  fn();
  std::filesystem::current_path(previous);
}

}  // namespace test
