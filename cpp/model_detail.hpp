// Internals of model loading, exposed for the tests.
#pragma once

#include <climits>
#include <cstddef>
#include <optional>
#include <string_view>

namespace simloop::detail {

// The most XML Model::from_xml_string takes: MuJoCo's virtual file system
// sizes its files with an int.
inline constexpr std::size_t kMaxXmlStringBytes = INT_MAX;

// Throws InvalidArgument naming `source` and the size unless `size` bytes of
// XML can go through MuJoCo's in-memory loader (1 .. kMaxXmlStringBytes).
void check_xml_size(std::size_t size, std::string_view source);

// The first character of a text past blanks and a UTF-8 byte order mark
// (none for a blank text): '<' for an MJCF scene, another for a scenario's TOML.
inline std::optional<char> first_visible(std::string_view text) {
  const std::size_t first = text.find_first_not_of(" \t\r\n\xEF\xBB\xBF");
  if (first == std::string_view::npos) return std::nullopt;
  return text[first];
}

}  // namespace simloop::detail
