#include "simloop/number_format.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <system_error>

#include "simloop/errors.hpp"

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

namespace {

// ---- std::to_chars(double)'s text, faster, for the numbers trajectories
// hold. std::to_chars (Ryu, in libstdc++) writes the shortest digits that read
// back as x, the closest of them to x, as fixed or scientific, whichever is
// shorter (fixed on a tie); it spends about 400 instructions a number, most
// of the cost of a trajectory.csv. For 2^-130 <= |x| < 2^53 the same digits
// come here from Schubfach (R. Giulietti, "The Schubfach way to render
// doubles", 2020) in about half of that: in that range every power of ten
// the method needs, 10^0 to 10^55, is an integer below 2^128, so its table
// is computed below rather than copied. Other numbers (and nan, inf) go to
// std::to_chars itself; tests/cpp/test_number_format.cc compares the two.

#ifdef __SIZEOF_INT128__
__extension__ typedef unsigned __int128 Uint128;

// 10^j as Schubfach wants it: g = floor(beta) + 1 for 10^j = beta * 2^r with
// 2^127 <= beta < 2^128 (here beta is 5^j shifted, an integer), and
// floor(log2(10^j)).
struct Pow10 {
  Uint128 g;
  int log2;
};
constexpr int kMaxPow10 = 55;  // 5^55 < 2^128 <= 5^56

constexpr std::array<Pow10, kMaxPow10 + 1> make_pow10() {
  std::array<Pow10, kMaxPow10 + 1> table{};
  Uint128 five = 1;  // 5^j
  for (int j = 0; j <= kMaxPow10; ++j) {
    int bits = 0;  // floor(log2(5^j))
    while ((five >> bits) > 1) ++bits;
    table[static_cast<std::size_t>(j)] = {(five << (127 - bits)) + 1, j + bits};
    if (j < kMaxPow10) five *= 5;
  }
  return table;
}
constexpr std::array<Pow10, kMaxPow10 + 1> kPow10 = make_pow10();

// floor(a / 2^22) for a <= 0, without relying on how >> treats negatives.
constexpr int floor_shift22(std::int64_t a) { return -static_cast<int>((-a + (1 << 22) - 1) >> 22); }

// floor(g * cp / 2^128), its lowest bit set if that dropped anything (round
// to odd; the low 64 bits of g's low half times cp are below what matters).
inline std::uint64_t round_to_odd(Uint128 g, std::uint64_t cp) {
  const Uint128 low = static_cast<Uint128>(static_cast<std::uint64_t>(g)) * cp;
  const Uint128 y =
      static_cast<Uint128>(static_cast<std::uint64_t>(g >> 64)) * cp + static_cast<std::uint64_t>(low >> 64);
  return static_cast<std::uint64_t>(y >> 64) | (static_cast<std::uint64_t>(y) != 0);
}

// The shortest digits * 10^exponent that read back as x (the closest such,
// ties to even digits), for x = c * 2^q, 2^52 <= c < 2^53, -182 <= q <= 0.
// The digits may end in zeros.
struct Decimal {
  std::uint64_t digits;
  int exponent;
};
inline Decimal shortest_decimal(std::uint64_t c, int q) {
  if (q >= -52) {  // an integer below 2^53: its own digits
    const std::uint64_t whole = c >> -q;
    if ((whole << -q) == c) return {whole, 0};
  }
  const bool even = (c & 1) == 0;
  const bool closer_below = c == (std::uint64_t{1} << 52);  // a power of two: the gap below is half
  // k = floor(log10(2^q)), or of 3/4 2^q when the gap below is half.
  const int k = floor_shift22(static_cast<std::int64_t>(q) * 1262611 - (closer_below ? 524031 : 0));
  const Pow10& p = kPow10[static_cast<std::size_t>(-k)];
  const int h = q + p.log2 + 1;  // 1 to 4
  const std::uint64_t cb = c << 2;
  const std::uint64_t vb = round_to_odd(p.g, cb << h);
  const std::uint64_t lower = round_to_odd(p.g, (cb - 2 + closer_below) << h) + !even;
  const std::uint64_t upper = round_to_odd(p.g, (cb + 2) << h) - !even;
  const std::uint64_t s = vb >> 2;
  if (s >= 10) {  // one digit fewer, if exactly one neighbour at that length reads back as x
    const std::uint64_t sp = s / 10;
    const bool down = lower <= 40 * sp, up = 40 * sp + 40 <= upper;
    if (down != up) return {sp + up, k + 1};
  }
  const bool down = lower <= 4 * s, up = 4 * s + 4 <= upper;
  if (down != up) return {s + up, k};
  const std::uint64_t mid = 4 * s + 2;  // both read back: the closer, ties to even
  return {s + (vb > mid || (vb == mid && (s & 1) != 0)), k};
}

constexpr char kTwoDigits[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

// The two digits of v < 100 at out.
inline void put2(char* out, std::uint32_t v) { std::memcpy(out, kTwoDigits + 2 * v, 2); }

// The eight digits of v < 10^8 at out (leading zeros included).
inline void put8(char* out, std::uint32_t v) {
  const std::uint32_t high = v / 10000, low = v % 10000;
  put2(out, high / 100);
  put2(out + 2, high % 100);
  put2(out + 4, low / 100);
  put2(out + 6, low % 100);
}

// How many decimal digits v >= 1 has: from its bit length, log10(2) ~ 1233 / 4096.
inline int decimal_length(std::uint64_t v) {
  static constexpr std::uint64_t kPowers[] = {1ull,
                                              10ull,
                                              100ull,
                                              1000ull,
                                              10000ull,
                                              100000ull,
                                              1000000ull,
                                              10000000ull,
                                              100000000ull,
                                              1000000000ull,
                                              10000000000ull,
                                              100000000000ull,
                                              1000000000000ull,
                                              10000000000000ull,
                                              100000000000000ull,
                                              1000000000000000ull,
                                              10000000000000000ull,
                                              100000000000000000ull,
                                              1000000000000000000ull,
                                              10000000000000000000ull};
  const int guess = ((64 - __builtin_clzll(v)) * 1233) >> 12;
  return guess + (v >= kPowers[guess]);
}

// Writes x's text at out (kShortestRoom bytes) and returns its end, or
// nullptr outside the range. Its copies are of fixed sizes: past the text's
// end they leave bytes that are not the text's.
char* write_shortest_fast(char* out, double x) noexcept {
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  if (bits >> 63) *out++ = '-';
  bits &= ~(std::uint64_t{1} << 63);
  if (bits == 0) {
    *out = '0';
    return out + 1;
  }
  const int biased = static_cast<int>(bits >> 52);
  if (biased < 1075 - 182 || biased > 1075) return nullptr;
  Decimal d = shortest_decimal((bits & ((std::uint64_t{1} << 52) - 1)) | (std::uint64_t{1} << 52), biased - 1075);
  while (d.digits % 10 == 0) {
    d.digits /= 10;
    ++d.exponent;
  }
  // The digits, left-aligned in a row of '0's (the zeros a whole number
  // ends with are already there); at most 17 of them.
  const int n = decimal_length(d.digits);
  char digits[32];
  std::memset(digits, '0', sizeof digits);
  char* end = digits + n;
  std::uint64_t v = d.digits;
  while (v >= 100000000) {
    end -= 8;
    put8(end, static_cast<std::uint32_t>(v % 100000000));
    v /= 100000000;
  }
  auto w = static_cast<std::uint32_t>(v);
  for (; w >= 100; w /= 100) {
    end -= 2;
    put2(end, w % 100);
  }
  if (w >= 10) {
    put2(end - 2, w);
  } else {
    end[-1] = static_cast<char>('0' + w);
  }
  // Laid out as std::to_chars lays them: fixed or scientific, whichever is
  // shorter, fixed on a tie. Here |x| < 2^53, so a fixed form has at most 16
  // digits before the point and, when it wins, at most 3 zeros after it.
  const int point = n + d.exponent;  // digits before the decimal point
  const int sci_exponent = point - 1;
  const int sci_length = n + (n > 1) + 2 + (sci_exponent <= -100 ? 3 : 2);
  const int fixed_length = d.exponent >= 0 ? point : point > 0 ? n + 1 : 2 - d.exponent;
  if (fixed_length <= sci_length) {
    if (d.exponent >= 0) {  // digits and zeros
      std::memcpy(out, digits, 16);
      return out + point;
    }
    if (point > 0) {  // digits.digits
      std::memcpy(out, digits, 16);
      out[point] = '.';
      std::memcpy(out + point + 1, digits + point, 16);
      return out + n + 1;
    }
    std::memcpy(out, "0.000", 5);  // 0.[000]digits
    std::memcpy(out + 2 - point, digits, 17);
    return out + fixed_length;
  }
  out[0] = digits[0];  // d[.digits]e-XX[X]
  out[1] = '.';
  std::memcpy(out + 2, digits + 1, 16);
  out += n > 1 ? n + 1 : 1;
  out[0] = 'e';
  out[1] = sci_exponent < 0 ? '-' : '+';
  int e = sci_exponent < 0 ? -sci_exponent : sci_exponent;
  if (e >= 100) {
    out[2] = static_cast<char>('0' + e / 100);
    put2(out + 3, static_cast<std::uint32_t>(e % 100));
    return out + 5;
  }
  put2(out + 2, static_cast<std::uint32_t>(e));
  return out + 4;
}
#else
char* write_shortest_fast(char*, double) noexcept { return nullptr; }
#endif

}  // namespace

char* write_shortest(char* out, double x) noexcept {
  if (char* end = write_shortest_fast(out, x)) return end;
  return std::to_chars(out, out + kMaxShortestChars, x).ptr;
}

void append_shortest(std::string& out, double x) {
  char buf[kShortestRoom];
  out.append(buf, write_shortest(buf, x));
}

std::string shortest_repr(double x) {
  std::string out;
  append_shortest(out, x);
  return out;
}

void check_count(std::string_view name, std::int64_t value, std::int64_t most) {
  if (value < 1) throw InvalidArgument(std::string(name) + " must be at least 1, got " + std::to_string(value));
  if (value > most) {
    throw InvalidArgument(std::string(name) + " must be at most " + std::to_string(most) + ", got " +
                          std::to_string(value));
  }
}

void check_positive_seconds(std::string_view name, double value) {
  if (std::isfinite(value) && value > 0.0) return;
  throw InvalidArgument(std::string(name) + " must be a positive, finite number of seconds, got " +
                        python_float_repr(value));
}

}  // namespace simloop
