// A scenario's CSV control schedule ([[control]] csv = "FILE"), read a
// bounded line at a time (text_input.hpp).
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "simloop/scenario.hpp"

namespace simloop::detail {

// One value per step from a CSV file: a header row, then a row per step
// (step 0 first). The column is `column`, or the only one. Only the steps
// where the value changes become schedule entries; after the last row the
// last value holds.
// `where` names the table and key in errors ("control[0].csv").
[[nodiscard]] std::vector<std::pair<When, double>> read_csv_schedule(const std::filesystem::path& file,
                                                                     const std::string& column,
                                                                     const std::string& where);

}  // namespace simloop::detail
