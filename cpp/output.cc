#include "simloop/output.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <system_error>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"

namespace simloop {
namespace {

// json.dumps writes a float as repr() does, except for the non-finite ones.
std::string json_float(double x) {
  if (std::isnan(x)) return "NaN";
  if (std::isinf(x)) return x > 0 ? "Infinity" : "-Infinity";
  return python_float_repr(x);
}

const char* json_bool(bool b) { return b ? "true" : "false"; }

[[noreturn]] void throw_io(const std::filesystem::path& path, std::string_view what, int err) {
  throw IoError(path.string() + ": " + std::string(what) + " (" + std::strerror(err) + ")");
}

// A temporary file beside its destination, removed unless committed.
class PendingFile {
 public:
  PendingFile(std::filesystem::path target, std::string_view contents) : target_(std::move(target)) {
    std::string pattern = (target_.parent_path() / ("." + target_.filename().string() + ".tmp.XXXXXX")).string();
    const int fd = ::mkstemp(pattern.data());
    if (fd < 0) throw_io(target_, "cannot create a temporary file beside it", errno);
    temp_ = pattern;
    size_t done = 0;
    while (done < contents.size()) {
      const ssize_t n = ::write(fd, contents.data() + done, contents.size() - done);
      if (n < 0) {
        if (errno == EINTR) continue;
        const int err = errno;
        ::close(fd);
        throw_io(target_, "cannot write", err);
      }
      done += static_cast<size_t>(n);
    }
    // mkstemp makes the file 0600; outputs are ordinary files.
    if (::fchmod(fd, 0644) != 0 || ::close(fd) != 0) throw_io(target_, "cannot write", errno);
  }
  PendingFile(const PendingFile&) = delete;
  PendingFile& operator=(const PendingFile&) = delete;
  ~PendingFile() {
    if (!temp_.empty()) ::unlink(temp_.c_str());
  }
  void commit() {
    if (::rename(temp_.c_str(), target_.c_str()) != 0) throw_io(target_, "cannot replace", errno);
    temp_.clear();
  }

 private:
  std::filesystem::path target_;
  std::string temp_;
};

}  // namespace

std::string metrics_json(const Metrics& m) {
  // Keys in sorted order, two-space indent, ", " never used: what json.dumps
  // writes with indent=2 and sort_keys=True.
  std::string out = "{\n  \"box_final_pos\": [\n";
  for (int i = 0; i < 3; ++i) {
    out += "    " + json_float(m.box_final_pos[i]) + (i < 2 ? ",\n" : "\n");
  }
  out += "  ],\n";
  out += "  \"box_final_speed\": " + json_float(m.box_final_speed) + ",\n";
  out += "  \"lateral_drift\": " + json_float(m.lateral_drift) + ",\n";
  out += std::string("  \"perturb\": ") + json_bool(m.perturb) + ",\n";
  out += "  \"pusher_final_x\": " + json_float(m.pusher_final_x) + ",\n";
  out += "  \"seed\": " + std::to_string(m.seed) + ",\n";
  out += std::string("  \"shove_moved_box\": ") + json_bool(m.shove_moved_box) + ",\n";
  out += "  \"steps\": " + std::to_string(m.steps) + "\n}\n";
  return out;
}

std::string trajectory_csv(const Trajectory& t) {
  std::string out;
  out.reserve(static_cast<size_t>(t.rows() + 1) * static_cast<size_t>(t.columns()) * 12);
  for (int c = 0; c < t.columns(); ++c) {
    if (c > 0) out += ',';
    out += Trajectory::kColumnNames[c];
  }
  out += '\n';
  for (std::int64_t r = 0; r < t.rows(); ++r) {
    for (int c = 0; c < t.columns(); ++c) {
      if (c > 0) out += ',';
      const double v = t.at(r, c);
      if (Trajectory::is_input_column(c) && std::isnan(v)) continue;  // final row: no inputs
      if (Trajectory::is_integer_column(c)) {
        out += std::to_string(static_cast<std::int64_t>(v));
      } else {
        append_shortest(out, v);
      }
    }
    out += '\n';
  }
  return out;
}

std::string summary_text(const RunResult& r) {
  const Metrics& m = r.metrics;
  char line[512];
  std::string out;
  std::snprintf(line, sizeof line, "stepped %lld steps of %s s -> %.2f s of sim time\n",
                static_cast<long long>(m.steps), python_float_repr(r.timestep).c_str(), r.sim_time);
  out += line;
  std::snprintf(line, sizeof line, "box final position [%.3f, %.3f, %.3f], speed %.3f m/s\n",
                m.box_final_pos[0], m.box_final_pos[1], m.box_final_pos[2], m.box_final_speed);
  out += line;
  if (m.perturb) {
    std::snprintf(line, sizeof line, "shove: %+.1f N in y for %lld steps -> %.3f m of sideways drift\n",
                  r.shove.force_y(), static_cast<long long>(r.shove.num_steps), m.lateral_drift);
  } else {
    std::snprintf(line, sizeof line, "no shove (baseline run)\n");
  }
  out += line;
  for (const Warning& w : r.warnings) {
    std::snprintf(line, sizeof line, "%s warning %s: raised %d time%s, first in step %lld: %s\n",
                  w.name.rfind("mj", 0) == 0 ? "MuJoCo" : "simloop", w.name.c_str(), w.count, w.count == 1 ? "" : "s", static_cast<long long>(w.first_step),
                  w.message.c_str());
    out += line;
  }
  if (r.config.audit_energy) {
    const EnergyTotals& e = r.energy;
    std::snprintf(line, sizeof line,
                  "energy audit: change %+.4f J = work by motor %+.4f, shove %+.4f, damping %+.4f, "
                  "contacts %+.4f (positive steps %+.4f) + unexplained %+.4f J\n",
                  e.energy_end - e.energy_start, e.work_actuator, e.work_shove, e.work_passive, e.work_constraint,
                  e.work_constraint_positive, e.unexplained);
    out += line;
  }
  if (!r.warnings.empty()) {
    out += "  (after a bad-value warning MuJoCo resets the state and carries on: "
           "the numbers above are not one continuous simulation)\n";
  }
  return out;
}

void prepare_output_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec)) {
    throw IoError(dir.string() + ": exists and is not a directory");
  }
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(dir.string() + ": cannot create the output directory (" + ec.message() + ")");
  std::string probe = (dir / ".simloop-probe.XXXXXX").string();
  const int fd = ::mkstemp(probe.data());
  if (fd < 0) throw IoError(dir.string() + ": cannot write in the output directory (" + std::strerror(errno) + ")");
  ::close(fd);
  ::unlink(probe.c_str());
}

void write_file_atomically(const std::filesystem::path& path, std::string_view contents) {
  PendingFile file(path, contents);
  file.commit();
}

OutputFiles write_outputs(const RunResult& result, const std::filesystem::path& dir) {
  prepare_output_dir(dir);
  OutputFiles files{dir / "metrics.json", dir / "trajectory.csv"};
  PendingFile metrics(files.metrics, metrics_json(result.metrics));
  PendingFile trajectory(files.trajectory, trajectory_csv(result.trajectory));
  trajectory.commit();
  metrics.commit();
  return files;
}

}  // namespace simloop
