#include "csv_schedule.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "simloop/errors.hpp"
#include "text_input.hpp"

namespace simloop::detail {

std::vector<std::pair<When, double>> read_csv_schedule(const std::filesystem::path& file, const std::string& column,
                                                       const std::string& where) {
  try {
    check_regular_file(file, "a CSV file");
  } catch (const Error& e) {
    throw InvalidArgument(where + ": " + e.what());
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw IoError(where + ": " + file.string() + ": cannot open (" + std::strerror(errno) + ")");
  const std::string source = where + ": " + file.string();
  std::int64_t line_number = 1;
  const auto next_line = [&](std::string& line) {
    return read_line(in, line, kMaxCsvLineBytes, source, line_number++);
  };
  const auto cells = [](const std::string& line) {
    std::vector<std::string> out(1);
    for (char c : line) {
      if (c == ',') {
        out.emplace_back();
      } else if (c != '\r') {
        out.back() += c;
      }
    }
    return out;
  };
  std::string line;
  if (!next_line(line)) throw InvalidArgument(where + ": " + file.string() + ": empty (it needs a header row)");
  const std::vector<std::string> header = cells(line);
  std::size_t index = 0;
  if (!column.empty()) {
    const auto it = std::find(header.begin(), header.end(), column);
    if (it == header.end()) {
      std::string names;
      for (const std::string& h : header) names += (names.empty() ? "" : ", ") + h;
      throw InvalidArgument(where + ": " + file.string() + " has no column '" + column + "'; its columns: " + names);
    }
    index = static_cast<std::size_t>(it - header.begin());
  } else if (header.size() != 1) {
    throw InvalidArgument(where + ": " + file.string() + " has " + std::to_string(header.size()) +
                          " columns: name the one to use (column = \"...\")");
  }
  std::vector<std::pair<When, double>> schedule;
  std::int64_t step = 0;
  for (; next_line(line); ++step) {
    const std::vector<std::string> row = cells(line);
    const std::string cell = index < row.size() ? row[index] : std::string();
    char* end = nullptr;
    const double value = std::strtod(cell.c_str(), &end);
    if (cell.empty() || end != cell.c_str() + cell.size() || !std::isfinite(value) ||
        std::isspace(static_cast<unsigned char>(cell[0]))) {
      throw InvalidArgument(where + ": " + file.string() + ":" + std::to_string(line_number - 1) +
                            ": expected a finite number, got " + quoted_value(cell, 40));
    }
    if (schedule.empty() || value != schedule.back().second) schedule.emplace_back(When::steps(step), value);
  }
  if (schedule.empty()) throw InvalidArgument(where + ": " + file.string() + ": no rows after the header");
  return schedule;
}

}  // namespace simloop::detail
