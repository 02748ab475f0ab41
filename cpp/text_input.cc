#include "text_input.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <istream>
#include <new>
#include <system_error>

#include "simloop/errors.hpp"

namespace simloop::detail {
namespace {

std::string mib(std::size_t bytes) { return std::to_string(bytes >> 20) + " MiB"; }

bool is_bare_key_char(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

}  // namespace

void check_path(const std::filesystem::path& path, std::string_view what) {
  const std::string& text = path.native();
  const std::size_t nul = text.find('\0');
  if (nul != std::string::npos) {
    throw InvalidArgument(std::string(what) + " " + quoted_value(text) +
                          ": a path cannot hold a NUL byte (the system would read only up to it)");
  }
}

void check_regular_file(const std::filesystem::path& path, std::string_view what) {
  check_path(path, what);
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(path, error);
  if (std::filesystem::is_directory(status)) {
    throw IoError(path.string() + ": is a directory, not " + std::string(what));
  }
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
    throw InvalidArgument(path.string() + ": is a device, a pipe or a socket, not " + std::string(what) +
                          " (simloop reads its inputs from files)");
  }
}

std::string read_text_file(const std::filesystem::path& path, std::size_t max_bytes, std::string_view what) {
  check_regular_file(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open (" + std::strerror(errno) + ")");
  std::string text;
  try {
    // Read in slices, not through operator<<(streambuf*): that one swallows
    // an allocation failure and leaves a shorter text behind.
    constexpr std::size_t kSlice = std::size_t{1} << 16;
    while (in) {
      const std::size_t at = text.size();
      if (at > max_bytes) break;
      text.resize(at + kSlice);
      in.read(text.data() + at, static_cast<std::streamsize>(kSlice));
      text.resize(at + static_cast<std::size_t>(in.gcount()));
    }
  } catch (const std::bad_alloc&) {
    throw IoError(path.string() + ": not enough memory to read it");
  }
  if (in.bad()) throw IoError(path.string() + ": cannot read (" + std::strerror(errno) + ")");
  if (text.size() > max_bytes) {
    throw InvalidArgument(path.string() + ": more than " + mib(max_bytes) + ", the most " + std::string(what) +
                          " may hold");
  }
  return text;
}

bool read_line(std::istream& in, std::string& line, std::size_t max_bytes, std::string_view source,
               std::int64_t line_number) {
  line.clear();
  try {
    for (int c = in.get(); c != std::char_traits<char>::eof(); c = in.get()) {
      if (c == '\n') return true;
      if (line.size() == max_bytes) {
        throw InvalidArgument(std::string(source) + ":" + std::to_string(line_number) + ": a line longer than " +
                              mib(max_bytes) + " (a row of a CSV schedule is a handful of numbers)");
      }
      line.push_back(static_cast<char>(c));
    }
  } catch (const std::bad_alloc&) {
    throw IoError(std::string(source) + ": not enough memory to read it");
  }
  if (in.bad()) throw IoError(std::string(source) + ": cannot read (" + std::strerror(errno) + ")");
  return !line.empty();
}

void check_toml_key_parts(std::string_view text, std::string_view source) {
  std::size_t line = 1;
  std::size_t line_start = 0;
  std::size_t i = 0;
  const auto skip_blanks = [&] {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
  };
  // One part of a key at i: a bare key, or a quoted one that ends on its line.
  const auto part = [&]() -> bool {
    if (i >= text.size()) return false;
    const char c = text[i];
    if (is_bare_key_char(c)) {
      while (i < text.size() && is_bare_key_char(text[i])) ++i;
      return true;
    }
    if (c != '"' && c != '\'') return false;
    for (++i; i < text.size() && text[i] != '\n'; ++i) {
      if (text[i] == '\\' && c == '"') {
        ++i;
      } else if (text[i] == c) {
        ++i;
        return true;
      }
    }
    return true;  // unterminated: the parser says so
  };
  while (i < text.size()) {
    if (text[i] == '\n') {
      ++line;
      line_start = ++i;
      continue;
    }
    const std::size_t start = i;
    if (!part()) {
      ++i;
      continue;
    }
    std::size_t parts = 1;
    for (;;) {
      const std::size_t before = i;
      skip_blanks();
      if (i >= text.size() || text[i] != '.') {
        i = before;
        break;
      }
      ++i;
      skip_blanks();
      if (!part()) break;
      if (++parts > kMaxTomlKeyParts) {
        throw InvalidArgument(std::string(source) + ":" + std::to_string(line) + ":" +
                              std::to_string(start - line_start + 1) + ": a key of more than " +
                              std::to_string(kMaxTomlKeyParts) +
                              " dotted parts (a.b.c has 3); a scenario's keys have at most 2");
      }
    }
  }
}

}  // namespace simloop::detail
