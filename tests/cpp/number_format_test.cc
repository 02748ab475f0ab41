// Number formatting must match Python's exactly: metrics.json is compared
// byte for byte with what the chapter's json.dumps writes. Expected strings
// were produced by CPython 3.11's repr() and round().
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>

#include "simloop/number_format.hpp"

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
      {0.1234565, 0.123456},   {5e-07, 0.0},           {1.5e-06, 2e-06},
      {2.5e-06, 3e-06},        {-1e-07, -0.0},         {2.675, 2.675},
      {1.0000005, 1.000001},   {123.4567895, 123.456789}, {4.849876402547829, 4.849876},
      {0.049897127410617, 0.049897}, {-5e-07, -0.0},   {1e+300, 1e+300},
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

}  // namespace
