#include "command.hpp"

#include <cstdio>
#include <new>
#include <system_error>
#include <utility>

#include "simloop/chapter_scene.hpp"
#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/scenario.hpp"
#include "simloop/sweep.hpp"
#include "simloop/version.hpp"

namespace simloop::cli {
namespace {

std::string line(const char* name, const std::filesystem::path& path, const std::string& more = "") {
  return std::string(name) + ": " + path.string() + more + "\n";
}

// A sweep's sweep.csv, written beside its place.
template <class Result>
std::unique_ptr<PendingFile> sweep_file(const std::filesystem::path& out, const Result& result) {
  auto file = std::make_unique<PendingFile>(out / "sweep.csv");
  file->append(sweep_csv(result));
  file->finish();
  return file;
}

// The rows and columns of trajectory.csv, for its report line.
template <class Result>
std::string shape(const Result& result, bool scenario) {
  return " (" + std::to_string(result.rows) + " rows" +
         (scenario ? ", " + std::to_string(result.columns.size()) + " columns" : std::string()) + ")";
}

}  // namespace

Orchestration::Orchestration(const std::vector<std::string>& args) : started_(std::chrono::steady_clock::now()) {
  // Parsed by the same parser, run by the Python package (plot: matplotlib; batch: pyarrow, Dask).
  if (!args.empty() && (args[0] == "plot" || args[0] == "batch")) {
    throw Failure(kExitUsage, args[0] + " is a command of the Python package: python -m simloop " + args[0] +
                                  " (see python -m simloop " + args[0] + " --help)");
  }
  try {
    opts_ = parse(args);
  } catch (const UsageError& e) {
    throw Failure(kExitUsage, e.what());
  }
}

void Orchestration::close() noexcept {
  // The temporary files first, so that a folder this run made is empty.
  pending_.reset();
  sweep_csv_.reset();
  drawn_.reset();
  std::error_code ignored;
  if (!made_.empty()) std::filesystem::remove(made_, ignored);  // only if empty: anything in it is kept
  made_.clear();
  out_lock_.reset();
}

std::string Orchestration::banner() {
  return printable("ch0.1-sim-loop | tier: cpu | " + mujoco_version() + " | simloop " + kVersion + "\n");
}

// Inputs first, so that a bad one costs nothing and changes nothing.
std::string Orchestration::load() {
  if (!opts_.scenario_path.empty()) {
    try {
      scenario_ = Scenario::from_toml_file(opts_.scenario_path);
    } catch (const Error& e) {
      throw Failure(kExitUsage, "--scenario: " + std::string(e.what()));
    } catch (const std::bad_alloc&) {  // toml++ parsing it, under a memory limit
      throw Failure(kExitRunFailed, "--scenario: " + opts_.scenario_path + ": out of memory while reading it");
    }
  }
  const std::string model_flag = scenario_                  ? "--scenario " + opts_.scenario_path
                                 : opts_.model_path.empty() ? "--model"
                                                            : "--model " + opts_.model_path;
  try {
    model_ = scenario_                  ? load_scene(*scenario_)
             : opts_.model_path.empty() ? pusher_scene()
                                        : Model::from_file(opts_.model_path);
  } catch (const Error& e) {
    const bool theirs = scenario_ ? !scenario_->scene.empty() : !opts_.model_path.empty();
    throw Failure(theirs ? kExitUsage : kExitRunFailed,
                  (scenario_ ? "--scenario: " : "--model: ") + std::string(e.what()));
  } catch (const std::bad_alloc&) {
    throw Failure(kExitRunFailed, model_flag + ": out of memory while loading the model");
  } catch (const std::exception& e) {
    throw Failure(kExitRunFailed, model_flag + ": while loading the model: " + e.what());
  }
  // What MuJoCo said while it loaded the scene, as it says what it warns
  // while stepping: on the report.
  return printable(load_warnings_text(*model_));
}

// What runs: a scenario (its names checked now, in the flags' words), or the
// chapter's loop, which needs the chapter's box and pusher.
void Orchestration::check() {
  try {
    // A --model with nothing to push runs as it is (gravity and whatever it
    // has), as a scenario with no controls and no shove.
    if ((opts_.is_scenario() || nothing_to_push(opts_, *model_)) && !scenario_) {
      scenario_ = scenario_from_flags(opts_, &*model_);
    }
    check_run_inputs(opts_, *model_, scenario());
  } catch (const std::exception& e) {
    throw Failure(kExitUsage, e.what());
  }
}

void Orchestration::open_output() {
  // Anything at --out, a link to nothing included, is the user's: never removed.
  std::error_code out_check;
  if (!std::filesystem::exists(std::filesystem::symlink_status(opts_.out, out_check))) made_ = opts_.out;
  try {
    prepare_output_dir(opts_.out);
    out_lock_.emplace(opts_.out);
  } catch (const OutputInUse& e) {
    made_.clear();  // the other run's folder now
    throw Failure(kExitUsage, "--out: " + std::string(e.what()));
  } catch (const std::exception& e) {
    throw Failure(kExitUsage, "--out: " + std::string(e.what()));
  }
}

// A failure as one line: what was being done, and what went wrong.
template <class Step>
void Orchestration::reporting(Step&& step) {
  try {
    step();
  } catch (const Interrupted&) {
    throw;
  } catch (const Failure&) {
    throw;
  } catch (const MujocoError& e) {
    throw Failure(kExitRunFailed, "MuJoCo error while " + doing() + ": " + e.what());
  } catch (const Error& e) {  // IoError names its file; InvalidArgument its input
    throw Failure(kExitRunFailed, e.what());
  } catch (const std::bad_alloc&) {
    throw Failure(kExitRunFailed, "out of memory while " + doing());
  } catch (const std::exception& e) {  // a thread that cannot be made, for one
    throw Failure(kExitRunFailed, "while " + doing() + ": " + e.what());
  }
}

void Orchestration::run(RunControl* control, bool drawn) {
  reporting([&] {
    if (sweep() && scenario_) {  // sweep --scenario, --body, --ctrl
      const auto result = sweep_scenario(*model_, *scenario_, opts_.sweep_timesteps, opts_.sweep_duration,
                                         scenario_config(opts_), opts_.threads, control);
      sweep_csv_ = sweep_file(opts_.out, result);
      sweep_summary_ = sweep_summary(result);
    } else if (sweep()) {
      const auto result = simloop::sweep(*model_, opts_.sweep_timesteps, opts_.sweep_duration, opts_.threads, control);
      sweep_csv_ = sweep_file(opts_.out, result);
      sweep_summary_ = sweep_summary(result);
    } else {
      if (drawn) drawn_ = std::make_unique<SpooledRows>(opts_.out);  // before anything else is written
      if (scenario_) {
        auto [result, outputs] =
            run_to_folder(*model_, *scenario_, scenario_config(opts_), opts_.out, drawn_.get(), control);
        record_.emplace(std::move(result));
        pending_.emplace(std::move(outputs));
      } else {
        auto [result, outputs] = run_to_folder(*model_, opts_.run, opts_.out, drawn_.get(), control);
        chapter_.emplace(std::move(result));
        pending_.emplace(std::move(outputs));
      }
    }
  });
}

void Orchestration::commit(const RunControl* control, const std::vector<PendingFile*>& also) {
  reporting([&] {
    if (sweep_csv_) {
      commit_together({sweep_csv_.get()}, control);
    } else {
      files_ = pending_->commit(control, also);
    }
    committed_ = true;
  });
}

std::string Orchestration::report(const std::string& drawn) const {
  if (sweep()) return printable(sweep_summary_ + line("sweep", opts_.out / "sweep.csv"));
  std::string text;
  // Which scene ran, when it is the user's own: the file, and, for a scene
  // with nothing to push, that nothing was.
  if (!opts_.model_path.empty() && opts_.scenario_path.empty()) text += line("model", opts_.model_path);
  if (scenario_ && nothing_to_push(opts_, *model_)) text += kNothingToPushLine;
  text += record_ ? summary_text(*record_) : summary_text(*chapter_);
  text += line("metrics", files_.metrics);
  text += line("trajectory", files_.trajectory, record_ ? shape(*record_, true) : shape(*chapter_, false));
  if (!drawn.empty()) {
    text += drawn + "\n";
  } else if (opts_.rerun) {
    text += "recording: none (sim_loop writes no .rrd; python -m simloop records one)\n";
  }
  return printable(text);
}

std::string Orchestration::plot_line(const std::filesystem::path& png) { return printable(line("plot", png)); }

std::string Orchestration::closing_line() const {
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  char wall[96];
  std::snprintf(wall, sizeof wall, "wall-clock: %.1f ms, peak memory: %.1f MiB\n", seconds * 1e3, peak_memory_mib());
  return wall;
}

std::string Orchestration::doing() const { return cli::doing(opts_, model_ ? &*model_ : nullptr, scenario()); }

// Read from /proc rather than getrusage: ru_maxrss also counts the memory of
// the process we were forked from, before our exec.
double peak_memory_mib() {
  std::FILE* status = std::fopen("/proc/self/status", "r");
  if (status == nullptr) return -1.0;
  char text[256];
  double mib = -1.0;
  while (std::fgets(text, sizeof text, status) != nullptr) {
    long long kib = 0;
    if (std::sscanf(text, "VmHWM: %lld kB", &kib) == 1) {
      mib = static_cast<double>(kib) / 1024.0;
      break;
    }
  }
  std::fclose(status);
  return mib;
}

}  // namespace simloop::cli
