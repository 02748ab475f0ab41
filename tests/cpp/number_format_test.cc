// Number formatting must match Python's exactly: metrics.json is compared
// byte for byte with what the chapter's json.dumps writes. Expected strings
// were produced by CPython 3.11's repr() and round().
#include "simloop/number_format.hpp"

#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>

namespace {

struct ReprCase {
  double value;
  const char* python_repr;
};

TEST(PythonFloatRepr, MatchesCPython) {
  const ReprCase cases[] = {
      {0.0, "0.0"},
      {-0.0, "-0.0"},
      {1.0, "1.0"},
      {4.0, "4.0"},
      {0.05, "0.05"},
      {0.002, "0.002"},
      {1e-05, "1e-05"},
      {-1e-05, "-1e-05"},
      {0.0001, "0.0001"},
      {0.00012345, "0.00012345"},
      {1e+16, "1e+16"},
      {1000000000000000.0, "1000000000000000.0"},
      {1.2345678901234568e+17, "1.2345678901234568e+17"},
      {1.5e-300, "1.5e-300"},
      {2.5, "2.5"},
      {0.30000000000000004, "0.30000000000000004"},
      {4.849876, "4.849876"},
      {0.3333333333333333, "0.3333333333333333"},
      {-7.25e+22, "-7.25e+22"},
      {5e-324, "5e-324"},
      {1.7976931348623157e+308, "1.7976931348623157e+308"},
      {0.000123, "0.000123"},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(simloop::python_float_repr(c.value), c.python_repr) << c.python_repr;
  }
  EXPECT_EQ(simloop::python_float_repr(std::numeric_limits<double>::quiet_NaN()), "nan");
  EXPECT_EQ(simloop::python_float_repr(-std::numeric_limits<double>::infinity()), "-inf");
}

TEST(Round6, MatchesPythonRound) {
  const std::pair<double, double> cases[] = {
      {0.1234565, 0.123456},
      {5e-07, 0.0},
      {1.5e-06, 2e-06},
      {2.5e-06, 3e-06},
      {-1e-07, -0.0},
      {2.675, 2.675},
      {1.0000005, 1.000001},
      {123.4567895, 123.456789},
      {4.849876402547829, 4.849876},
      {0.049897127410617, 0.049897},
      {-5e-07, -0.0},
      {1e+300, 1e+300},
      {3.0517578125e-05, 3.1e-05},
  };
  for (const auto& [value, rounded] : cases) {
    const double got = simloop::round6(value);
    EXPECT_EQ(got, rounded) << value;
    EXPECT_EQ(std::signbit(got), std::signbit(rounded)) << value;
  }
  EXPECT_TRUE(std::isnan(simloop::round6(std::numeric_limits<double>::quiet_NaN())));
}

TEST(ShortestRepr, RoundTripsExactly) {
  std::mt19937_64 gen(7);
  for (int i = 0; i < 100000; ++i) {
    double x;
    const std::uint64_t bits = gen();
    std::memcpy(&x, &bits, sizeof x);
    if (!std::isfinite(x)) continue;
    const std::string text = simloop::shortest_repr(x);
    const double back = std::strtod(text.c_str(), nullptr);
    ASSERT_EQ(std::memcmp(&back, &x, sizeof x), 0) << text;
  }
  EXPECT_EQ(simloop::shortest_repr(0.002), "0.002");
  EXPECT_EQ(simloop::shortest_repr(1.0), "1");
}

// write_shortest has its own digits for 2^-130 <= |x| < 2^53 and hands the
// rest to std::to_chars: both must write std::to_chars's bytes.
void expect_to_chars_bytes(double x) {
  char expected[64], got[simloop::kShortestRoom];
  const std::string expected_text(expected, std::to_chars(expected, expected + sizeof expected, x).ptr);
  const std::string got_text(got, simloop::write_shortest(got, x));
  ASSERT_EQ(got_text, expected_text) << std::hexfloat << x;
}

double from_bits(std::uint64_t bits) {
  double x;
  std::memcpy(&x, &bits, sizeof x);
  return x;
}

TEST(WriteShortest, WritesStdToCharsBytes) {
  std::mt19937_64 gen(11);
  // Every binary exponent in the fast range and around it, random digits,
  // and the powers of two (whose gap below is half) with their neighbours.
  for (std::uint64_t biased = 850; biased <= 1100; ++biased) {
    for (int i = 0; i < 400; ++i) {
      const double x = from_bits((biased << 52) | (gen() >> 12));
      expect_to_chars_bytes(x);
      expect_to_chars_bytes(-x);
    }
    for (std::uint64_t ulps = 0; ulps < 4; ++ulps) {
      expect_to_chars_bytes(from_bits((biased << 52) + ulps));
      expect_to_chars_bytes(from_bits((biased << 52) - ulps - 1));
    }
  }
  // Short decimals (their shortest digits are short, their layout varies:
  // 0.0001, 1e-05, 123000, 1.5e+15), whole numbers, the steps of a timestep.
  for (int exponent = -42; exponent <= 17; ++exponent) {
    for (int digits = 1; digits <= 17; ++digits) {
      for (int i = 0; i < 20; ++i) {
        const std::string mantissa =
            std::to_string(gen() % 100000000000000000ull).substr(0, static_cast<size_t>(digits));
        expect_to_chars_bytes(std::strtod((mantissa + "e" + std::to_string(exponent)).c_str(), nullptr));
      }
    }
  }
  for (int i = 0; i <= 20000; ++i) {
    expect_to_chars_bytes(i);
    expect_to_chars_bytes(i * 0.002);
    expect_to_chars_bytes(i / 7.0);
  }
  // Anything at all, and the edges.
  for (int i = 0; i < 100000; ++i) expect_to_chars_bytes(from_bits(gen()));
  const double edges[] = {0.0,
                          -0.0,
                          5e-324,
                          -2.2250738585072014e-308,
                          1.7976931348623157e308,
                          0x1p-130,
                          0x1p-131,
                          0x1p53,
                          0x1p53 - 1,
                          0x1p52 + 0.5,
                          1e15,
                          1e16,
                          0.0001,
                          1e-05,
                          std::numeric_limits<double>::infinity(),
                          -std::numeric_limits<double>::infinity(),
                          std::numeric_limits<double>::quiet_NaN()};
  for (const double x : edges) expect_to_chars_bytes(x);
}

}  // namespace
