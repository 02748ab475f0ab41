// sim_loop's flags: the chapter's, spelled and defaulted as there, plus
// --model, --record-every, --help and --version, and the scenario flags
// (--scenario, --body, --ctrl). Parsed in cli_options.cc; turned into what
// runs (a scenario, its checks, its config) in cli_scenario.cc; --help in
// cli_help.cc; what it was doing, for error lines, in cli_doing.cc; the
// `batch` command's flags (python -m simloop's) in cli_batch.cc.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "simloop/model.hpp"
#include "simloop/run.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scenario_run.hpp"

namespace simloop::cli {

enum class Command { kRun, kSweep, kPlot, kBatch };

// The most runs one batch takes: python -m simloop holds each run's
// parameters (196 bytes measured, so about 2 GB at this) before the first
// starts. A larger study is split into batches.
inline constexpr std::uint64_t kMaxBatchRuns = 10'000'000;
// The most runs in one chunk (--chunk-size; an executor's chunk_size).
inline constexpr std::int64_t kMaxChunkRuns = 2'147'483'647;

// seeds first, first + step, ... up to last (inclusive: a range may end at 2^64-1).
struct SeedRange {
  std::uint64_t first = 0;
  std::uint64_t last = 0;
  std::uint64_t step = 1;
  [[nodiscard]] std::uint64_t count() const noexcept { return (last - first) / step + 1; }
};

// One axis of a batch's grid: --friction, --mass, --damping or --gravity.
struct BatchParam {
  std::string kind;  // friction, mass, damping or gravity
  std::string name;  // the geom, body or joint; "" : every one (gravity: always)
  std::vector<double> values;
};

// `batch` (python -m simloop's): a scenario over seeds and a grid of scene
// parameters. What the scene must check (names, values, the rng's name, the
// timesteps' range) is the library's, once the scenario is loaded.
struct BatchOptions {
  std::string scenario;                 // --scenario FILE; "" : the chapter's run
  std::vector<SeedRange> seeds = {{}};  // --seeds (default 0)
  std::vector<double> timesteps;        // --timestep; empty: the scenario's own
  std::vector<BatchParam> params;       // in the order given
  std::int64_t steps = 0;               // --steps; 0: the scenario's length
  std::string rng = "mt19937_64";       // --rng
  bool perturb = true;                  // --no-perturb
  std::string scheduler;                // --scheduler; "" : this machine's threads
  int threads = 0;                      // --threads; 0: the command's default
  std::int64_t chunk_size = 0;          // --chunk-size; 0: the command's default
  std::filesystem::path out = "outputs/batch.parquet";
  bool resume = false;
};

struct Options {
  Command command = Command::kRun;
  RunConfig run;
  // `sweep`: the timesteps (empty: the default range), the span, the workers.
  std::vector<double> sweep_timesteps;
  double sweep_duration = 4.0;
  bool sweep_duration_given = false;  // --duration was given (a scenario sweep's default is the scenario's length)
  int threads = 0;                    // 0: one per core
  // `plot` (python -m simloop's): what to draw from --out's CSV, the runs
  // drawn beside it (--compare) and the x axis (--x: auto, time or step).
  std::string plot_what;
  std::vector<std::filesystem::path> plot_compare;
  std::string plot_x = "auto";
  BatchOptions batch;  // `batch`'s flags (cli_batch.cc)
  bool plot = false;   // --plot: trajectory.png / sweep.png
  std::filesystem::path out = "outputs/ch0.1-sim-loop";
  std::string model_path;  // empty: the embedded pusher scene
  // Your scene, your loop (a scenario instead of the chapter's fixed run):
  std::string scenario_path;                          // --scenario FILE (TOML)
  std::string body;                                   // --body NAME: the body the chapter's shove acts on ("" : box)
  std::vector<std::pair<std::string, double>> ctrls;  // --ctrl ACTUATOR=VALUE, in order
  bool timestep_given = false;                        // --timestep was given (else the scene's or scenario's own)
  bool steps_given = false;                           // --steps or --smoke was given (else the scenario's length)
  bool rng_given = false;                             // --rng was given
  bool chapter = false;                               // --chapter: the book's run as closely as this build allows
  bool rerun = true;            // accepted for the chapter's command lines; sim_loop records nothing
  std::filesystem::path video;  // --video FILE: pictures of the run (python -m simloop only)
  bool help = false;
  bool version = false;

  // True when the run is a scenario (--scenario, --body or --ctrl), not the
  // chapter's fixed run with its exact outputs.
  [[nodiscard]] bool is_scenario() const noexcept { return !scenario_path.empty() || !body.empty() || !ctrls.empty(); }
};

// A bad command line. The message is one line naming the flag and the value.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Parses argv (argv[0] is skipped). Accepts "--flag value" and "--flag=value".
// Shared by sim_loop and `python -m simloop`, so both take the same flags and
// refuse bad ones with the same words.
[[nodiscard]] Options parse(int argc, const char* const* argv);
// The same for the arguments alone, without the program's name.
[[nodiscard]] Options parse(const std::vector<std::string>& args);
// parse's for argv[1] == "batch" (cli_batch.cc). Its messages begin "batch: ".
[[nodiscard]] Options parse_batch(int argc, const char* const* argv);

// A plain decimal number: [-]digits[.digits][e[+-]digits], at least one
// digit before the exponent. No spaces, '+' signs, hex, inf or nan: every
// flag's numbers are read by this one rule.
[[nodiscard]] bool plain_decimal(std::string_view s);

// `s`'s parts between each `by` (one part, `s`, when it has none; empty
// parts kept): how every flag's list (a,b,c) and range (A:B:STEP) is read.
[[nodiscard]] std::vector<std::string_view> split(std::string_view s, char by);

// The scenario the quick flags describe (--body, --ctrl; a --scenario file
// is read with Scenario::from_toml_file): the chapter's run on `scene` (the
// --model, or the chapter's): the chapter's shove on --body, a body's name
// or index (default box on the chapter's scene; on a --model, no shove
// without --body),
// the --ctrl values held from step 0 (default: actuator 0 at 1.0, as the
// chapter writes ctrl[0]), recording every body on a free joint, the pushed
// body and every actuator. The scene's own timestep unless --timestep.
[[nodiscard]] Scenario scenario_from_flags(const Options& opts, const Model* scene = nullptr);

// True for a run (not a sweep) of a --model alone (no --scenario, --body or
// --ctrl) whose scene has nothing to push: no body a force can move (every
// body welded to the world) and no actuator. The chapter's loop cannot run
// it and --body could name no body; it runs as scenario_from_flags has it
// (gravity and whatever the scene has, recording what moves), and the
// summary says so with kNothingToPushLine.
[[nodiscard]] bool nothing_to_push(const Options& opts, const Model& scene);
inline constexpr const char* kNothingToPushLine =
    "nothing could be pushed: the scene has no body a force can move and no actuator; it ran as it is\n";

// Checks what is about to run against its scene, in the words of the flags
// (UsageError): a scenario's names (with did-you-mean, and what the scene
// has), or, for the chapter's run, that the scene has the chapter's box and
// pusher. The chapter's run on a --model keeps the scene's own timestep
// unless --timestep was given (written into opts.run).
void check_run_inputs(Options& opts, const Model& scene, const Scenario* scenario);

// A scenario sweep (sweep with --scenario, --body or --ctrl): the span is
// --duration or else the scenario's own length (scenario_duration), the
// timesteps --timesteps/--range or else the default grid's that give every
// run at least kMinSweepSteps steps; every point is checked (UsageError in
// the flags' words). check_run_inputs calls it for a sweep.
void complete_scenario_sweep(Options& opts, const Model& scene, const Scenario& scenario);

// What --seed, --rng, --timestep, --steps/--smoke, --no-perturb and
// --record-every ask of a scenario run.
[[nodiscard]] ScenarioConfig scenario_config(const Options& opts);

// What the command was doing, with which inputs, for its error lines
// (command/cli_doing.cc): "running 2000 steps of --model x.xml (--steps 2000,
// --timestep 0.002, --record-every 1)" or "sweeping ...". With the scene and
// scenario of a scenario run, the timestep and steps it ran with: the
// flags', else the scenario's, else the scene's own.
[[nodiscard]] std::string doing(const Options& opts, const Model* scene = nullptr, const Scenario* scenario = nullptr);

// --help for `program`; `recording` says what --rerun does there, `plot`
// what --plot does.
[[nodiscard]] std::string help_text(std::string_view program, std::string_view recording);
[[nodiscard]] std::string sweep_help_text(std::string_view program);

}  // namespace simloop::cli
