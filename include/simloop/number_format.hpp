// Number formatting that other tools read back exactly.
#pragma once

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

}  // namespace simloop
