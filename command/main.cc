// sim_loop: the command's one orchestration (command.cc), in this process:
// its report on stdout, its failures on stderr, its signals, its progress bar
// and --plot through the Python package (process.cc, plot.cc). It writes no
// recording; python -m simloop runs the same orchestration and records one.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "command.hpp"
#include "sim_loop.hpp"
#include "simloop/model.hpp"
#include "simloop/version.hpp"

namespace sim_loop {
namespace {

class ProcessHost final : public simloop::cli::Host {
 public:
  [[nodiscard]] std::string help(bool sweep) const override {
    if (sweep) return simloop::cli::sweep_help_text("sim_loop");
    return simloop::cli::help_text("sim_loop",
                                   "accepted so the chapter's command lines work; sim_loop\n"
                                   "                    writes no recording (python -m simloop does)");
  }
  [[nodiscard]] std::string version() const override {
    return std::string("sim_loop ") + simloop::kVersion + " (" + simloop::mujoco_version() + ")";
  }
  void print(std::string_view text) override { std::fwrite(text.data(), 1, text.size(), stdout); }
  void flush() override {
    if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
      throw simloop::cli::Failure(kExitRunFailed, std::string("cannot write the report to standard output (") +
                                                      std::strerror(errno) + "); nothing was run");
    }
  }
  int fail(int code, const std::string& line) override { return sim_loop::fail(code, line); }
  void loading(bool now) override {
    // While the model loads (which cannot be stopped between chunks) nothing
    // is half-done: a signal ends the process at once.
    g_exit_at_once = now ? 1 : 0;
    if (now && g_signal != 0) on_stop_signal(g_signal);
  }
  void work(const char* /*label*/, const std::function<void(simloop::RunControl*)>& work) override {
    check_stop();
    g_progress.start();
    work(&g_control);
    g_progress.finish();
  }
  void outputs_written() override { g_outputs_written = true; }
  std::filesystem::path plot(const std::filesystem::path& out, const char* what) override {
    return plot_with_python(out, what);
  }
  std::unique_ptr<simloop::cli::Recording> recording(const simloop::cli::Options& opts, const simloop::Model&,
                                                     const simloop::Scenario*) override {
    if (!opts.video.empty()) {
      throw simloop::cli::Failure(kExitUsage, "--video: sim_loop draws no pictures; python -m simloop --video " +
                                                  opts.video.string() + " does (nothing was written)");
    }
    return nullptr;
  }
  int interrupted() override { return sim_loop::interrupted(); }
  int stop_code() override { return g_control.stop_requested() ? sim_loop::interrupted() : 0; }
};

int run_main(int argc, char** argv) {
  if (!keep_standard_streams_open()) {
    return fail(kExitRunFailed, "standard output is closed; nothing was run (the report would be lost)");
  }
  install_signal_handlers();
  ProcessHost host;
  return simloop::cli::run_command(std::vector<std::string>(argv + 1, argv + argc), host);
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
