// Figures that depend on the MuJoCo version the tests run on, from one table
// per version: tests/expected/mujoco-<version>.toml (the Python tests read the
// same files). A test that needs one on a version without a table skips,
// saying so; every other check still runs.
#pragma once

#include <mujoco/mujoco.h>
#include <toml++/toml.h>

#include <optional>
#include <string>
#include <string_view>

namespace test {

inline std::string expected_figures_path() {
  return std::string(SIMLOOP_TEST_EXPECTED) + "/mujoco-" + mj_versionString() + ".toml";
}

inline const toml::table* expected_figures() {
  static const std::optional<toml::table> table = []() -> std::optional<toml::table> {
    try {
      return toml::parse_file(expected_figures_path());
    } catch (const toml::parse_error&) {
      return std::nullopt;
    }
  }();
  return table ? &*table : nullptr;
}

// The figure at `key` ("break_it.coarse_final_y_max"), or nothing.
template <class T>
std::optional<T> expected(std::string_view key) {
  const toml::table* table = expected_figures();
  if (table == nullptr) return std::nullopt;
  return table->at_path(key).value<T>();
}

inline std::string no_expected_figure(std::string_view key) {
  return "no figure '" + std::string(key) + "' for MuJoCo " + mj_versionString() + " in " + expected_figures_path();
}

}  // namespace test

// Declares `const type name` from the table, or skips the test saying why.
#define SIMLOOP_EXPECTED(type, name, key)                                  \
  const std::optional<type> name##_expected = ::test::expected<type>(key); \
  if (!name##_expected) GTEST_SKIP() << ::test::no_expected_figure(key);   \
  const type name = *name##_expected
