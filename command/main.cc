// sim_loop: parses flags, calls the library, reports. All simulation lives in
// simloop::run; this file only turns its results and errors into text and
// exit codes (the process's signals, streams and failures: process.cc; --plot:
// plot.cc).
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <new>
#include <optional>
#include <string>
#include <system_error>

#include "cli_options.hpp"
#include "sim_loop.hpp"
#include "simloop/control.hpp"
#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/output.hpp"
#include "simloop/output_lock.hpp"
#include "simloop/run.hpp"
#include "simloop/sweep.hpp"
#include "simloop/version.hpp"

namespace sim_loop {
namespace {

// A sweep's outputs: sweep.csv put in place, the summary, the plot if asked.
int report_sweep(const simloop::cli::Options& opts, const std::string& csv_text, const std::string& summary) {
  const std::filesystem::path csv = opts.out / "sweep.csv";
  simloop::PendingFile file(csv);
  file.append(csv_text);
  file.finish();
  simloop::commit_together({&file}, &g_control);
  g_outputs_written = true;
  g_progress.finish();
  std::fputs(summary.c_str(), stdout);
  std::printf("sweep: %s\n", csv.c_str());
  if (opts.plot) {
    const int status = plot_with_python(opts.out, "sweep");
    if (status != 0) return status;
    std::printf("plot: %s\n", (opts.out / "sweep.png").c_str());
  }
  return 0;
}

int sweep_command(const simloop::cli::Options& opts, const simloop::Model& model) {
  const simloop::SweepResult result =
      simloop::sweep(model, opts.sweep_timesteps, opts.sweep_duration, opts.threads, &g_control);
  return report_sweep(opts, simloop::sweep_csv(result), simloop::sweep_summary(result));
}

// sweep --scenario, --body, --ctrl: the scenario at every timestep.
int scenario_sweep_command(const simloop::cli::Options& opts, const simloop::Scenario& scenario,
                           const simloop::Model& scene) {
  const simloop::ScenarioSweepResult result =
      simloop::sweep_scenario(scene, scenario, opts.sweep_timesteps, opts.sweep_duration,
                              simloop::cli::scenario_config(opts), opts.threads, &g_control);
  return report_sweep(opts, simloop::scenario_sweep_csv(result), simloop::scenario_sweep_summary(result));
}

int run_command(const simloop::cli::Options& opts, const simloop::Model& model) {
  // The trajectory goes to its file as the loop steps, so memory stays
  // bounded however long the run; both outputs are put in place together at
  // the end, or (an error, a signal) neither.
  simloop::OutputWriter writer(opts.out);
  simloop::Data workspace(model);
  const simloop::RunResult result = simloop::run(model, opts.run, workspace, &writer.trajectory(), &g_control);
  const simloop::OutputFiles files = writer.commit(result.metrics, &g_control);
  g_outputs_written = true;
  g_progress.finish();
  std::fputs(simloop::summary_text(result).c_str(), stdout);
  std::printf("metrics: %s\n", files.metrics.c_str());
  std::printf("trajectory: %s (%lld rows)\n", files.trajectory.c_str(), static_cast<long long>(result.rows));
  if (opts.rerun) {
    std::printf("recording: none (sim_loop writes no .rrd; python -m simloop records one)\n");
  }
  if (opts.plot) {
    const int status = plot_with_python(opts.out, "trajectory");
    if (status != 0) return status;
    std::printf("plot: %s\n", (opts.out / "trajectory.png").c_str());
  }
  return 0;
}

// A scenario's run (--scenario, --body, --ctrl): the same streaming and
// committing as the chapter's, with the scenario's columns and metrics.
int scenario_command(const simloop::cli::Options& opts, const simloop::Scenario& scenario,
                     const simloop::Model& scene) {
  simloop::OutputWriter writer(opts.out);
  const simloop::RunRecord result = simloop::run_scenario(
      scene, scenario, simloop::cli::scenario_config(opts), nullptr, &writer.trajectory(), &g_control);
  const simloop::OutputFiles files = writer.commit(simloop::metrics_json(result), &g_control);
  g_outputs_written = true;
  g_progress.finish();
  std::fputs(simloop::summary_text(result).c_str(), stdout);
  std::printf("metrics: %s\n", files.metrics.c_str());
  std::printf("trajectory: %s (%lld rows, %zu columns)\n", files.trajectory.c_str(),
              static_cast<long long>(result.rows), result.columns.size());
  if (opts.rerun) {
    std::printf("recording: none (sim_loop writes no .rrd; python -m simloop records one)\n");
  }
  return 0;
}

int run_main(int argc, char** argv) {
  const auto started = std::chrono::steady_clock::now();
  namespace cli = simloop::cli;
  if (!keep_standard_streams_open()) {
    return fail(kExitRunFailed, "standard output is closed; nothing was run (the report would be lost)");
  }
  install_signal_handlers();
  cli::Options opts;
  try {
    opts = cli::parse(argc, argv);
  } catch (const cli::UsageError& e) {
    return fail(kExitUsage, e.what());
  }
  if (opts.help && opts.command == cli::Command::kSweep) {
    std::fputs(cli::sweep_help_text("sim_loop").c_str(), stdout);
    return 0;
  }
  if (opts.help) {
    std::fputs(cli::help_text("sim_loop",
                              "accepted so the chapter's command lines work; sim_loop\n"
                              "                    writes no recording (python -m simloop does)")
                   .c_str(),
               stdout);
    return 0;
  }
  if (opts.version) {
    std::printf("sim_loop %s (%s)\n", simloop::kVersion, simloop::mujoco_version().c_str());
    return 0;
  }

  // Banner: the chapter's startup contract (tier; wall-clock comes at the end).
  std::printf("ch0.1-sim-loop | tier: cpu | %s | simloop %s\n", simloop::mujoco_version().c_str(),
              simloop::kVersion);
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    return fail(kExitRunFailed, std::string("cannot write the report to standard output (") + std::strerror(errno) +
                                    "); nothing was run");
  }

  // Inputs first, so that a bad one costs nothing and changes nothing. A
  // signal while the model loads ends the process at once: nothing is
  // half-written yet.
  std::optional<simloop::Model> model;
  std::optional<simloop::Scenario> scenario;
  g_exit_at_once = 1;
  if (g_signal != 0) on_stop_signal(g_signal);
  if (!opts.scenario_path.empty()) {
    try {
      scenario = simloop::Scenario::from_toml_file(opts.scenario_path);
    } catch (const simloop::Error& e) {
      g_exit_at_once = 0;
      return fail(kExitUsage, "--scenario: " + std::string(e.what()));
    }
  }
  const std::string model_flag = scenario ? "--scenario " + opts.scenario_path
                                 : opts.model_path.empty() ? "--model" : "--model " + opts.model_path;
  try {
    model = scenario                   ? simloop::load_scene(*scenario)
            : opts.model_path.empty() ? simloop::pusher_scene()
                                      : simloop::Model::from_file(opts.model_path);
  } catch (const simloop::Error& e) {
    g_exit_at_once = 0;
    const bool theirs = scenario ? !scenario->scene.empty() : !opts.model_path.empty();
    return fail(theirs ? kExitUsage : kExitRunFailed, (scenario ? "--scenario: " : "--model: ") + std::string(e.what()));
  } catch (const std::bad_alloc&) {
    g_exit_at_once = 0;
    return fail(kExitRunFailed, model_flag + ": out of memory while loading the model");
  } catch (const std::exception& e) {
    g_exit_at_once = 0;
    return fail(kExitRunFailed, model_flag + ": while loading the model: " + e.what());
  }
  // What MuJoCo said while it loaded the scene, as it says what it warns
  // while stepping: on the report.
  std::fputs(simloop::load_warnings_text(*model).c_str(), stdout);
  // What runs: a scenario (its names checked now, in the flags' words), or
  // the chapter's loop, which needs the chapter's box and pusher.
  try {
    if (opts.is_scenario() && !scenario) scenario = simloop::cli::scenario_from_flags(opts, &*model);
    simloop::cli::check_run_inputs(opts, *model, scenario ? &*scenario : nullptr);
  } catch (const std::exception& e) {
    g_exit_at_once = 0;
    return fail(kExitUsage, e.what());
  }
  // From here on a file may exist that must go (the output directory's
  // probe, then the temporary outputs): a signal only requests a stop.
  g_exit_at_once = 0;
  std::error_code out_check;
  const bool out_existed = std::filesystem::exists(opts.out, out_check);
  // The run holds --out's lock for the rest of its life (one run at a time
  // in a folder); declared first, it is released last, after the folder's
  // removal below.
  std::optional<simloop::OutputLock> out_lock;
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
    simloop::prepare_output_dir(opts.out);
    out_lock.emplace(opts.out);
  } catch (const simloop::OutputInUse& e) {
    made.dir.clear();  // the other run's folder now
    return fail(kExitUsage, "--out: " + std::string(e.what()));
  } catch (const std::exception& e) {
    return fail(kExitUsage, "--out: " + std::string(e.what()));
  }

  // For error lines: what ran, with the timestep and steps it ran with.
  const auto doing_now = [&] { return simloop::cli::doing(opts, &*model, scenario ? &*scenario : nullptr); };
  try {
    check_stop();
    g_progress.start();
    const bool sweeping = opts.command == cli::Command::kSweep;
    const int status = sweeping && scenario ? scenario_sweep_command(opts, *scenario, *model)
                       : sweeping           ? sweep_command(opts, *model)
                       : scenario           ? scenario_command(opts, *scenario, *model)
                                            : run_command(opts, *model);
    if (status != 0) return status;
  } catch (const simloop::Interrupted&) {
    return interrupted();
  } catch (const simloop::MujocoError& e) {
    return fail(kExitRunFailed, "MuJoCo error while " + doing_now() + ": " + e.what());
  } catch (const simloop::Error& e) {  // IoError names its file; InvalidArgument its input
    return fail(kExitRunFailed, e.what());
  } catch (const std::bad_alloc&) {
    return fail(kExitRunFailed, "out of memory while " + doing_now());
  } catch (const std::system_error& e) {  // threads that cannot be made, for one
    return fail(kExitRunFailed, "while " + doing_now() + ": " + e.what());
  } catch (const std::exception& e) {
    return fail(kExitRunFailed, "while " + doing_now() + ": " + e.what());
  }
  if (g_control.stop_requested()) return interrupted();  // after the outputs were put in place
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::printf("wall-clock: %.1f ms, peak memory: %.1f MiB\n", seconds * 1e3, peak_memory_mib());
  return 0;
}

}  // namespace
}  // namespace sim_loop

int main(int argc, char** argv) {
  int code = sim_loop::kExitRunFailed;
  try {
    code = sim_loop::run_main(argc, argv);
  } catch (...) {  // a bug, but never a crash: say so in one line
    code = sim_loop::fail(sim_loop::kExitRunFailed, "internal error (please report it)");
  }
  return sim_loop::finish_stdout(code);
}
