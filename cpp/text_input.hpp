// Reading a user's text inputs (scenario files, their CSV schedules) with
// limits: no input, however large, endless or deep, can exhaust memory or the
// stack, and a read that fails is an error naming the file, never a shorter
// text.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <string_view>

namespace simloop::detail {

// The most a scenario file may hold: far past any hand-written or generated
// scenario (a million-step schedule_steps is ~10 MiB), far below memory.
inline constexpr std::size_t kMaxScenarioBytes = std::size_t{64} << 20;

// The longest line of a CSV schedule: a row is a handful of numbers.
inline constexpr std::size_t kMaxCsvLineBytes = std::size_t{1} << 20;

// The most dotted parts a TOML key may have (`[a.b.c]` has 3): scenario files
// need 2; toml++ recurses once per part, and 50,000 overflow the stack.
inline constexpr std::size_t kMaxTomlKeyParts = 64;

// Throws InvalidArgument when a path holds a NUL byte: the system would read
// it only up to the NUL, another file than the one named.
void check_path(const std::filesystem::path& path, std::string_view what);

// Throws IoError naming `path` when it is a folder, InvalidArgument when it
// is a device, a pipe or a socket: simloop reads its inputs from files (a
// pipe with no writer would block the open, /dev/zero never end).
void check_regular_file(const std::filesystem::path& path, std::string_view what);

// The whole regular file at `path`, at most `max_bytes` (check_path and
// check_regular_file first): IoError naming the path when it cannot be
// opened or read or memory runs out, InvalidArgument when it holds more.
[[nodiscard]] std::string read_text_file(const std::filesystem::path& path, std::size_t max_bytes,
                                         std::string_view what);

// One line of `in` (without its '\n') into `line`, at most `max_bytes`; false
// at the end of the input. Throws InvalidArgument naming `source` and the line
// when it is longer, IoError when the read fails.
bool read_line(std::istream& in, std::string& line, std::size_t max_bytes, std::string_view source,
               std::int64_t line_number);

// Throws InvalidArgument "source:line:column: a key of N dotted parts ..."
// when a key or table header of `text` has more than kMaxTomlKeyParts parts.
// Scans the text as a tokenizer would, without recursion, so any text passes
// through it in linear time; it may over-count only inside multi-line strings.
void check_toml_key_parts(std::string_view text, std::string_view source);

}  // namespace simloop::detail
