// sim_loop: the command's one orchestration (command.cc) in this process,
// step by step: its report on stdout, its failures on stderr, its signals,
// its progress bar and --plot through the Python package (process.cc,
// plot.cc). It writes no recording; python -m simloop takes the same steps
// and records one.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "command.hpp"
#include "sim_loop.hpp"
#include "simloop/errors.hpp"
#include "simloop/model.hpp"
#include "simloop/version.hpp"

namespace sim_loop {
namespace {

using simloop::cli::Failure;
using simloop::cli::Orchestration;

void print(const std::string& text) { std::fwrite(text.data(), 1, text.size(), stdout); }

std::string help(bool sweep) {
  if (sweep) return simloop::cli::sweep_help_text("sim_loop");
  return simloop::cli::help_text("sim_loop",
                                 "accepted so the chapter's command lines work; sim_loop\n"
                                 "                    writes no recording (python -m simloop does)");
}

// The inputs loaded and checked. While the model loads (which cannot be
// stopped between chunks) nothing is half-done: a signal ends the process at once.
void load(Orchestration& command) {
  g_exit_at_once = 1;
  if (g_signal != 0) on_stop_signal(g_signal);
  try {
    print(command.load());
    command.check();
  } catch (...) {
    g_exit_at_once = 0;
    throw;
  }
  g_exit_at_once = 0;
}

// From the output folder to the report's last line but one.
void run(Orchestration& command) {
  const simloop::cli::Options& opts = command.options();
  command.open_output();
  if (!opts.video.empty() && !command.sweep()) {
    throw Failure(kExitUsage, "--video: sim_loop draws no pictures; python -m simloop --video " + opts.video.string() +
                                  " does (nothing was written)");
  }
  check_stop();
  g_progress.start();
  command.run(&g_control, false);
  command.commit(&g_control);
  g_progress.finish();
  g_outputs_written = true;
  print(command.report(""));
  if (opts.plot) print(Orchestration::plot_line(plot_with_python(opts.out, command.sweep() ? "sweep" : "trajectory")));
}

int run_main(int argc, char** argv) {
  if (!keep_standard_streams_open()) {
    return fail(kExitRunFailed, "standard output is closed; nothing was run (the report would be lost)");
  }
  install_signal_handlers();
  std::optional<Orchestration> command;
  try {
    command.emplace(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const Failure& e) {
    return fail(e.code, e.what());
  }
  const simloop::cli::Options& opts = command->options();
  if (opts.help || opts.version) {
    print(simloop::printable(opts.help ? help(command->sweep())
                                       : std::string("sim_loop ") + simloop::kVersion + " (" +
                                             simloop::mujoco_version() + ")\n"));
    return 0;
  }
  print(Orchestration::banner());
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    return fail(kExitRunFailed, std::string("cannot write the report to standard output (") + std::strerror(errno) +
                                    "); nothing was run");
  }
  try {
    load(*command);
    run(*command);
  } catch (const simloop::Interrupted&) {
    return interrupted();
  } catch (const Failure& e) {
    return fail(e.code, e.what());
  } catch (const std::exception& e) {  // the plot's child that cannot be made, for one
    return fail(kExitRunFailed, "while " + command->doing() + ": " + e.what());
  }
  if (g_control.stop_requested()) return interrupted();  // after the outputs were put in place
  print(command->closing_line());
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
