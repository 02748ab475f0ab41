#include "simloop/number_format.hpp"

#include "simloop/errors.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <system_error>

namespace simloop {

double round6(double x) noexcept {
  if (!std::isfinite(x)) return x;
  // printf rounds the exact binary value to nearest, ties to even, as
  // Python's round() does through dtoa; strtod then returns the nearest double.
  char buf[400];  // |x| < 1.8e308: 309 digits, sign, point, 6 decimals
  std::snprintf(buf, sizeof buf, "%.6f", x);
  return std::strtod(buf, nullptr);
}

std::string python_float_repr(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  // Shortest round-trip digits and exponent, then Python's layout rules
  // (Python/pystrtod.c, repr mode 'r'): exponent form when the decimal point
  // would sit more than 16 digits right or 4 or more zeros left.
  char sci[32];
  const auto res = std::to_chars(sci, sci + sizeof sci - 1, x, std::chars_format::scientific);
  *res.ptr = '\0';
  const char* p = sci;
  std::string out;
  if (*p == '-') {
    out += '-';
    ++p;
  }
  std::string digits;
  for (; p < res.ptr && *p != 'e'; ++p) {
    if (*p != '.') digits += *p;
  }
  const int exponent = std::atoi(p + 1);  // p points at 'e'
  const int decpt = exponent + 1;
  const int ndigits = static_cast<int>(digits.size());
  if (decpt > 16 || decpt <= -4) {
    out += digits[0];
    if (ndigits > 1) {
      out += '.';
      out.append(digits, 1, std::string::npos);
    }
    char exp[16];
    std::snprintf(exp, sizeof exp, "e%c%02d", exponent < 0 ? '-' : '+', std::abs(exponent));
    out += exp;
  } else if (decpt <= 0) {
    out += "0.";
    out.append(static_cast<size_t>(-decpt), '0');
    out += digits;
  } else if (decpt >= ndigits) {
    out += digits;
    out.append(static_cast<size_t>(decpt - ndigits), '0');
    out += ".0";
  } else {
    out.append(digits, 0, static_cast<size_t>(decpt));
    out += '.';
    out.append(digits, static_cast<size_t>(decpt), std::string::npos);
  }
  return out;
}

void append_shortest(std::string& out, double x) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, res.ptr);
}

std::string shortest_repr(double x) {
  std::string out;
  append_shortest(out, x);
  return out;
}

void check_positive_seconds(std::string_view name, double value) {
  if (std::isfinite(value) && value > 0.0) return;
  throw InvalidArgument(std::string(name) + " must be a positive, finite number of seconds, got " +
                        python_float_repr(value));
}

}  // namespace simloop
