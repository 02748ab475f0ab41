// Internals of model loading, exposed for the tests.
#pragma once

#include <climits>
#include <cstddef>
#include <string_view>

namespace simloop::detail {

// The most XML Model::from_xml_string takes: MuJoCo's virtual file system
// sizes its files with an int.
inline constexpr std::size_t kMaxXmlStringBytes = INT_MAX;

// Throws InvalidArgument naming `source` and the size unless `size` bytes of
// XML can go through MuJoCo's in-memory loader (1 .. kMaxXmlStringBytes).
void check_xml_size(std::size_t size, std::string_view source);

}  // namespace simloop::detail
