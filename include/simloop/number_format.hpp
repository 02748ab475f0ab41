// Number formatting that other tools read back exactly.
#pragma once

#include <cstddef>
#include <string>

namespace simloop {

// Python's round(x, 6): the double nearest to x rounded half-even at the
// sixth decimal of its exact binary value.
[[nodiscard]] double round6(double x) noexcept;

// Python's repr(float): the shortest text that reads back as x, in Python's
// layout ("0.05", "1e-05", "4.0", "-0.0", "1e+16", "nan", "inf").
[[nodiscard]] std::string python_float_repr(double x);

// The shortest text that reads back as x, for CSV ("0.05", "1e-05", "4",
// "-0", "nan", "inf"); strtod, Python's float() and numpy read these exactly.
[[nodiscard]] std::string shortest_repr(double x);

// Appends shortest_repr(x) to out without a temporary string.
void append_shortest(std::string& out, double x);

// The longest text shortest_repr writes ("-2.2250738585072014e-308").
inline constexpr std::size_t kMaxShortestChars = 24;
// The room write_shortest needs at `out`: it works in place, in copies of
// fixed sizes, and may write bytes past its text's end (never past this).
inline constexpr std::size_t kShortestRoom = 48;

// Writes shortest_repr(x) at out, which has room for kShortestRoom bytes,
// and returns the end of its text: the bytes std::to_chars(double) writes.
char* write_shortest(char* out, double x) noexcept;

}  // namespace simloop
