#include "command.hpp"

#include <chrono>
#include <cstdio>
#include <new>
#include <optional>
#include <system_error>

#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/output_lock.hpp"
#include "simloop/scenario.hpp"
#include "simloop/sweep.hpp"
#include "simloop/version.hpp"

namespace simloop::cli {
namespace {

// Everything the report prints: names and paths of the user's reach it, and
// a control character among them is shown, never sent to the terminal.
void print(Host& host, std::string_view text) { host.print(printable(text)); }

std::string line(const char* name, const std::filesystem::path& path, const std::string& more = "") {
  return std::string(name) + ": " + path.string() + more + "\n";
}

// What a failure says, as one line and an exit code.
int report_failure(Host& host, const std::exception_ptr& error, const std::string& doing) {
  try {
    std::rethrow_exception(error);
  } catch (const Interrupted&) {
    return host.interrupted();
  } catch (const Failure& e) {
    return host.fail(e.code, e.what());
  } catch (const MujocoError& e) {
    return host.fail(kExitRunFailed, "MuJoCo error while " + doing + ": " + e.what());
  } catch (const Error& e) {  // IoError names its file; InvalidArgument its input
    return host.fail(kExitRunFailed, e.what());
  } catch (const std::bad_alloc&) {
    return host.fail(kExitRunFailed, "out of memory while " + doing);
  } catch (const std::exception& e) {  // a thread that cannot be made, for one
    return host.fail(kExitRunFailed, "while " + doing + ": " + e.what());
  }
}

// A sweep's outputs: sweep.csv put in place, then the summary, and the plot if asked.
template <class Sweep>
int sweep_into(Host& host, const Options& opts, Sweep&& sweep) {
  const std::filesystem::path csv = opts.out / "sweep.csv";
  std::string summary;
  host.work("sweeping", [&](RunControl* control) {
    const auto result = sweep(control);
    PendingFile file(csv);
    file.append(sweep_csv(result));
    file.finish();
    commit_together({&file}, control);
    summary = sweep_summary(result);
  });
  host.outputs_written();
  print(host, summary);
  print(host, line("sweep", csv));
  if (opts.plot) print(host, line("plot", host.plot(opts.out, "sweep")));
  return 0;
}

// A run into --out (run_to_folder: its files and the recording's, if any,
// put in place together, or none of them), then its report.
template <class Run>
int run_into(Host& host, const Options& opts, const Model& model, const Scenario* scenario, Run&& run) {
  std::unique_ptr<Recording> recording;
  if (opts.rerun || !opts.video.empty())
    recording = host.recording(opts, model, scenario);  // begun before anything is written
  std::optional<decltype(run(recording.get(), nullptr))> done;
  host.work("running", [&](RunControl* control) { done.emplace(run(recording.get(), control)); });
  host.outputs_written();
  const auto& [result, files] = *done;
  // Which scene ran, when it is the user's own: the file, and, for a scene
  // with nothing to push, that nothing was.
  if (!opts.model_path.empty() && opts.scenario_path.empty()) print(host, line("model", opts.model_path));
  if (scenario != nullptr && nothing_to_push(opts, model)) print(host, kNothingToPushLine);
  print(host, summary_text(result));
  print(host, line("metrics", files.metrics));
  print(host, line("trajectory", files.trajectory,
                   " (" + std::to_string(result.rows) + " rows" +
                       (scenario ? ", " + std::to_string(result.columns.size()) + " columns" : std::string()) + ")"));
  if (recording) {
    print(host, recording->line() + "\n");
  } else if (opts.rerun) {
    print(host, "recording: none (sim_loop writes no .rrd; python -m simloop records one)\n");
  }
  if (opts.plot) print(host, line("plot", host.plot(opts.out, "trajectory")));
  return 0;
}

int run_or_sweep(Host& host, const Options& opts, const Model& model, const Scenario* scenario) {
  if (opts.command == Command::kSweep && scenario) {  // sweep --scenario, --body, --ctrl
    return sweep_into(host, opts, [&](RunControl* control) {
      return sweep_scenario(model, *scenario, opts.sweep_timesteps, opts.sweep_duration, scenario_config(opts),
                            opts.threads, control);
    });
  }
  if (opts.command == Command::kSweep) {
    return sweep_into(host, opts, [&](RunControl* control) {
      return sweep(model, opts.sweep_timesteps, opts.sweep_duration, opts.threads, control);
    });
  }
  if (scenario) {
    return run_into(host, opts, model, scenario, [&](Recording* recording, RunControl* control) {
      return run_to_folder(model, *scenario, scenario_config(opts), opts.out, recording, control);
    });
  }
  return run_into(host, opts, model, nullptr, [&](Recording* recording, RunControl* control) {
    return run_to_folder(model, opts.run, opts.out, recording, control);
  });
}

}  // namespace

int run_command(const std::vector<std::string>& args, Host& host) {
  const auto started = std::chrono::steady_clock::now();
  Options opts;
  try {
    opts = parse(args);
  } catch (const UsageError& e) {
    return host.fail(kExitUsage, e.what());
  }
  if (opts.help) {
    print(host, host.help(opts.command == Command::kSweep));
    return 0;
  }
  if (opts.version) {
    print(host, host.version() + "\n");
    return 0;
  }
  // The banner: the chapter's startup contract (the tier; wall-clock at the end).
  print(host, "ch0.1-sim-loop | tier: cpu | " + mujoco_version() + " | simloop " + kVersion + "\n");
  try {
    host.flush();
  } catch (const Failure& e) {
    return host.fail(e.code, e.what());
  }

  // Inputs first, so that a bad one costs nothing and changes nothing.
  const auto refuse = [&](int code, const std::string& text) {
    host.loading(false);
    return host.fail(code, text);
  };
  host.loading(true);
  std::optional<Scenario> scenario;
  std::optional<Model> model;
  if (!opts.scenario_path.empty()) {
    try {
      scenario = Scenario::from_toml_file(opts.scenario_path);
    } catch (const Error& e) {
      return refuse(kExitUsage, "--scenario: " + std::string(e.what()));
    } catch (const std::bad_alloc&) {  // toml++ parsing it, under a memory limit
      return refuse(kExitRunFailed, "--scenario: " + opts.scenario_path + ": out of memory while reading it");
    }
  }
  const std::string model_flag = scenario                  ? "--scenario " + opts.scenario_path
                                 : opts.model_path.empty() ? "--model"
                                                           : "--model " + opts.model_path;
  try {
    model = scenario                  ? load_scene(*scenario)
            : opts.model_path.empty() ? pusher_scene()
                                      : Model::from_file(opts.model_path);
  } catch (const Error& e) {
    const bool theirs = scenario ? !scenario->scene.empty() : !opts.model_path.empty();
    return refuse(theirs ? kExitUsage : kExitRunFailed,
                  (scenario ? "--scenario: " : "--model: ") + std::string(e.what()));
  } catch (const std::bad_alloc&) {
    return refuse(kExitRunFailed, model_flag + ": out of memory while loading the model");
  } catch (const std::exception& e) {
    return refuse(kExitRunFailed, model_flag + ": while loading the model: " + e.what());
  }
  // What MuJoCo said while it loaded the scene, as it says what it warns
  // while stepping: on the report.
  print(host, load_warnings_text(*model));
  // What runs: a scenario (its names checked now, in the flags' words), or
  // the chapter's loop, which needs the chapter's box and pusher.
  try {
    // A --model with nothing to push runs as it is (gravity and whatever it
    // has), as a scenario with no controls and no shove.
    if ((opts.is_scenario() || nothing_to_push(opts, *model)) && !scenario) {
      scenario = scenario_from_flags(opts, &*model);
    }
    check_run_inputs(opts, *model, scenario ? &*scenario : nullptr);
  } catch (const std::exception& e) {
    return refuse(kExitUsage, e.what());
  }
  // From here on a file may exist that must go (the output directory's
  // probe, then the temporary outputs): a signal only requests a stop.
  host.loading(false);
  // Anything at --out, a link to nothing included, is the user's: never removed.
  std::error_code out_check;
  const bool out_existed = std::filesystem::exists(std::filesystem::symlink_status(opts.out, out_check));
  // --out's lock, held for the rest of the run (one run at a time in a
  // folder); declared first, it is released last, after the folder's removal.
  std::optional<OutputLock> out_lock;
  // A folder this run makes goes again if the run leaves nothing in it (a
  // failed or interrupted run): remove() takes only an empty directory.
  struct RemoveIfLeftEmpty {
    std::filesystem::path dir;
    ~RemoveIfLeftEmpty() {
      std::error_code ignored;
      if (!dir.empty()) std::filesystem::remove(dir, ignored);
    }
  } made{out_existed ? std::filesystem::path() : opts.out};
  try {
    prepare_output_dir(opts.out);
    out_lock.emplace(opts.out);
  } catch (const OutputInUse& e) {
    made.dir.clear();  // the other run's folder now
    return host.fail(kExitUsage, "--out: " + std::string(e.what()));
  } catch (const std::exception& e) {
    return host.fail(kExitUsage, "--out: " + std::string(e.what()));
  }

  try {
    const int status = run_or_sweep(host, opts, *model, scenario ? &*scenario : nullptr);
    if (status != 0) return status;
  } catch (...) {
    const std::exception_ptr error = std::current_exception();
    if (host.passes_through(error)) throw;
    return report_failure(host, error, doing(opts, &*model, scenario ? &*scenario : nullptr));
  }
  if (const int code = host.stop_code(); code != 0) return code;  // after the outputs were put in place
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  char wall[96];
  std::snprintf(wall, sizeof wall, "wall-clock: %.1f ms, peak memory: %.1f MiB\n", seconds * 1e3, peak_memory_mib());
  print(host, wall);
  return 0;
}

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
