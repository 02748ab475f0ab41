// What a run leaves behind: metrics.json, trajectory.csv, and the summary
// lines the commands print. The library writes files only when asked to, and
// always atomically.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "simloop/run.hpp"

namespace simloop {

// The text Python's json.dumps(metrics, indent=2, sort_keys=True) + "\n"
// writes for the chapter's metrics dict, byte for byte.
[[nodiscard]] std::string metrics_json(const Metrics& metrics);

// trajectory.csv: a header of Trajectory::kColumnNames, then one line per row.
// Numbers are the shortest text that reads back as the same double; step and
// ncon are whole numbers; the final row's input cells are empty.
[[nodiscard]] std::string trajectory_csv(const Trajectory& trajectory);

// The chapter's closing lines: steps and sim time, where the box ended, the
// shove and its drift (or "no shove (baseline run)"), and any MuJoCo
// warnings. Each line ends in "\n". Nothing in it depends on time or machine.
[[nodiscard]] std::string summary_text(const RunResult& result);

// Creates `dir` (and parents) if missing and checks that files can be
// created in it. Throws IoError naming the directory.
void prepare_output_dir(const std::filesystem::path& dir);

// Replaces `path` with `contents` atomically: a temporary file in the same
// directory, then rename, so readers see the old file or the new, never a
// half-written one. Throws IoError naming the path; the old file is kept.
void write_file_atomically(const std::filesystem::path& path, std::string_view contents);

struct OutputFiles {
  std::filesystem::path metrics;     // <dir>/metrics.json
  std::filesystem::path trajectory;  // <dir>/trajectory.csv
};

// Writes metrics.json and trajectory.csv into `dir` (prepared first). Both are
// written to temporary files before either is renamed into place, so a
// failure leaves the earlier outputs as they were.
OutputFiles write_outputs(const RunResult& result, const std::filesystem::path& dir);

}  // namespace simloop
