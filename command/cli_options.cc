#include "cli_options.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <optional>
#include <string_view>

#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/sweep.hpp"

namespace simloop::cli {
namespace {

// A value as the user typed it, in single quotes, on one line: a quote or
// backslash gets a backslash, control characters are written \xNN.
std::string quoted(std::string_view value) {
  std::string out = "'";
  for (const char c : value) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '\'' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte < 0x20 || byte == 0x7f) {
      static constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[byte >> 4];
      out += kHex[byte & 0xf];
    } else {
      out += c;
    }
  }
  return out + "'";
}

// A plain decimal number: [-]digits[.digits][e[+-]digits], at least one
// digit before the exponent. No spaces, '+' signs, hex, inf or nan: the same
// strictness as the whole numbers get.
bool plain_decimal(std::string_view s) {
  size_t i = 0;
  if (i < s.size() && s[i] == '-') ++i;
  size_t digits = 0;
  while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i, ++digits;
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i, ++digits;
  }
  if (digits == 0) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    size_t exponent_digits = 0;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i, ++exponent_digits;
    if (exponent_digits == 0) return false;
  }
  return i == s.size();
}

bool all_digits(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

std::uint64_t parse_u64(std::string_view flag, std::string_view value, std::uint64_t min, std::uint64_t max) {
  errno = 0;
  const std::string text(value);
  const unsigned long long n = all_digits(text) ? std::strtoull(text.c_str(), nullptr, 10) : 0;
  if (!all_digits(text) || errno == ERANGE || n < min || n > max) {
    throw UsageError(std::string(flag) + " must be a whole number from " + std::to_string(min) + " to " +
                     std::to_string(max) + ", got " + quoted(value));
  }
  return n;
}

double parse_timestep(std::string_view flag, std::string_view value) {
  const std::string text(value);
  const bool plain = plain_decimal(text);
  const double x = plain ? std::strtod(text.c_str(), nullptr) : 0.0;
  if (!plain || !std::isfinite(x) || !(x > 0.0)) {
    throw UsageError(std::string(flag) + " must be a positive, finite number of seconds, got " + quoted(value));
  }
  return x;
}

// ACTUATOR=VALUE: an actuator by name or index, and any finite number.
std::pair<std::string, double> parse_ctrl(std::string_view flag, std::string_view value) {
  const size_t eq = value.rfind('=');
  const std::string number = eq == std::string_view::npos ? std::string() : std::string(value.substr(eq + 1));
  const bool plain = plain_decimal(number);
  const double x = plain ? std::strtod(number.c_str(), nullptr) : 0.0;
  if (eq == 0 || eq == std::string_view::npos || !plain || !std::isfinite(x)) {
    throw UsageError(std::string(flag) + " must be ACTUATOR=VALUE (an actuator's name or index, a finite number), got " +
                     quoted(value));
  }
  return {std::string(value.substr(0, eq)), x};
}

std::vector<double> parse_timestep_list(std::string_view flag, std::string_view value) {
  std::vector<double> out;
  size_t start = 0;
  while (true) {
    const size_t comma = value.find(',', start);
    const std::string_view item = value.substr(start, comma == std::string_view::npos ? comma : comma - start);
    out.push_back(parse_timestep(flag, item));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

// FROM:TO:COUNT, log-spaced.
std::vector<double> parse_range(std::string_view flag, std::string_view value) {
  const size_t a = value.find(':');
  const size_t b = a == std::string_view::npos ? a : value.find(':', a + 1);
  if (b == std::string_view::npos) {
    throw UsageError(std::string(flag) + " must be FROM:TO:COUNT, got " + quoted(value));
  }
  const double from = parse_timestep(flag, value.substr(0, a));
  const double to = parse_timestep(flag, value.substr(a + 1, b - a - 1));
  const auto count = static_cast<int>(parse_u64(flag, value.substr(b + 1), 1, 10000));
  try {
    return log_spaced(from, to, count);
  } catch (const std::exception& e) {
    throw UsageError(std::string(flag) + ": " + e.what() + ", got " + quoted(value));
  }
}

}  // namespace

Options parse(int argc, const char* const* argv) {
  Options opts;
  const char* timesteps_flag = "--duration";  // what set the sweep's timesteps
  int first = 1;
  if (argc > 1 && std::string_view(argv[1]) == "sweep") {
    opts.command = Command::kSweep;
    first = 2;
  }
  const bool sweeping = opts.command == Command::kSweep;
  for (int i = first; i < argc; ++i) {
    std::string_view arg = argv[i];
    std::optional<std::string_view> inline_value;
    if (const auto eq = arg.find('='); arg.rfind("--", 0) == 0 && eq != std::string_view::npos) {
      inline_value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
    }
    const auto value = [&]() -> std::string_view {
      if (inline_value) return *inline_value;
      if (i + 1 >= argc) throw UsageError(std::string(arg) + " needs a value");
      return argv[++i];
    };
    const auto no_value = [&] {
      if (inline_value) throw UsageError(std::string(arg) + " takes no value, got " + quoted(*inline_value));
    };
    const auto run_only = [&] {
      if (sweeping) throw UsageError(std::string(arg) + " is not a sweep option (see sweep --help)");
    };
    const auto sweep_only = [&] {
      if (!sweeping) throw UsageError(std::string(arg) + " belongs to the sweep command: sim_loop sweep " + std::string(arg));
    };
    if (arg == "--timesteps") {
      sweep_only();
      opts.sweep_timesteps = parse_timestep_list(arg, value());
      timesteps_flag = "--timesteps/--duration";
    } else if (arg == "--range") {
      sweep_only();
      opts.sweep_timesteps = parse_range(arg, value());
      timesteps_flag = "--range/--duration";
    } else if (arg == "--duration") {
      sweep_only();
      const std::string_view v = value();
      try {
        opts.sweep_duration = parse_timestep(arg, v);
        opts.sweep_duration_given = true;
      } catch (const UsageError&) {
        throw UsageError("--duration must be a positive, finite number of seconds, got " + quoted(v));
      }
    } else if (arg == "--threads") {
      sweep_only();
      opts.threads = static_cast<int>(parse_u64(arg, value(), 1, 4096));
    } else if (arg == "--plot") {
      no_value();
      opts.plot = true;
    } else if (arg == "--seed") {
      run_only();
      opts.run.seed = parse_u64(arg, value(), 0, std::numeric_limits<std::uint64_t>::max());
    } else if (arg == "--rng") {
      run_only();
      const std::string_view v = value();
      const std::optional<ShoveRng> rng = parse_rng(v);
      if (!rng) throw UsageError("--rng must be mt19937_64 or numpy, got " + quoted(v));
      opts.run.rng = *rng;
    } else if (arg == "--steps") {
      run_only();
      opts.run.steps = static_cast<std::int64_t>(parse_u64(arg, value(), 1, static_cast<std::uint64_t>(kMaxSteps)));
      opts.steps_given = true;
    } else if (arg == "--timestep") {
      run_only();
      opts.run.timestep = parse_timestep(arg, value());
      opts.timestep_given = true;
    } else if (arg == "--scenario") {
      const std::string_view v = value();
      if (v.empty()) throw UsageError("--scenario must name a scenario file (TOML), got ''");
      opts.scenario_path = std::string(v);
    } else if (arg == "--body") {
      const std::string_view v = value();
      if (v.empty()) throw UsageError("--body must name a body of the scene (or give its index), got ''");
      opts.body = std::string(v);
    } else if (arg == "--ctrl") {
      opts.ctrls.push_back(parse_ctrl(arg, value()));
    } else if (arg == "--record-every") {
      run_only();
      opts.run.record_every =
          static_cast<std::int64_t>(parse_u64(arg, value(), 1, static_cast<std::uint64_t>(kMaxRecordEvery)));
    } else if (arg == "--out") {
      const std::string_view v = value();
      if (v.empty()) throw UsageError("--out must name a directory, got ''");
      opts.out = std::string(v);
    } else if (arg == "--model") {
      const std::string_view v = value();
      if (v.empty()) throw UsageError("--model must name an MJCF file, got ''");
      opts.model_path = std::string(v);
    } else if (arg == "--smoke") {
      run_only();
      no_value();
      opts.run.smoke = true;
      opts.steps_given = true;
    } else if (arg == "--energy-audit") {
      run_only();
      no_value();
      opts.run.audit_energy = true;
    } else if (arg == "--no-perturb") {
      run_only();
      no_value();
      opts.run.perturb = false;
    } else if (arg == "--rerun") {
      run_only();
      no_value();
      opts.rerun = true;
    } else if (arg == "--no-rerun") {
      run_only();
      no_value();
      opts.rerun = false;
    } else if (arg == "--help" || arg == "-h") {
      no_value();
      opts.help = true;
    } else if (arg == "--version") {
      no_value();
      opts.version = true;
    } else if (arg.rfind("-", 0) == 0) {
      throw UsageError("unknown option " + quoted(arg) + " (see --help)");
    } else {
      throw UsageError("unexpected argument " + quoted(arg) + " (see --help)");
    }
  }
  if (sweeping && opts.is_scenario()) {
    // A scenario sweep: its span and grid depend on the scenario and its
    // scene (complete_scenario_sweep, once they are loaded).
    if (!opts.scenario_path.empty() && !opts.model_path.empty()) {
      throw UsageError("--model and --scenario: the scenario file names its scene");
    }
    if (!opts.scenario_path.empty() && (!opts.body.empty() || !opts.ctrls.empty())) {
      throw UsageError(std::string(opts.body.empty() ? "--ctrl" : "--body") +
                       " and --scenario: the scenario file says what is pushed and driven");
    }
    return opts;
  }
  if (sweeping) {
    if (opts.sweep_timesteps.empty()) opts.sweep_timesteps = default_sweep_timesteps();
    // Every point must be runnable as asked (sweep_steps): say so now, in
    // the flags' words, rather than run something else or fail midway.
    for (const double dt : opts.sweep_timesteps) {
      if (opts.help || opts.version) break;
      try {
        (void)sweep_steps(opts.sweep_duration, dt);
      } catch (const std::exception& e) {
        throw UsageError(std::string(timesteps_flag) + ": " + e.what());
      }
    }
    return opts;
  }
  if (!opts.scenario_path.empty()) {
    if (!opts.model_path.empty()) throw UsageError("--model and --scenario: the scenario file names its scene");
    if (!opts.body.empty() || !opts.ctrls.empty()) {
      throw UsageError(std::string(opts.body.empty() ? "--ctrl" : "--body") +
                       " and --scenario: the scenario file says what is pushed and driven");
    }
  }
  if (opts.is_scenario() && opts.plot) {
    throw UsageError("--plot draws the chapter's run (its box and pusher); a scenario's trajectory.csv has the "
                     "scene's own columns (not with --scenario, --body or --ctrl)");
  }
  if (opts.is_scenario() && opts.run.audit_energy) {
    throw UsageError("--energy-audit accounts for the chapter's box and pusher only (not with --scenario, --body or --ctrl)");
  }
  // The library would refuse it too; say it in the flags' words.
  try {
    validate(opts.run);
  } catch (const std::exception& e) {
    throw UsageError(std::string("--steps/--record-every: ") + e.what());
  }
  return opts;
}

Scenario scenario_from_flags(const Options& opts, const Model* scene) {
  Scenario s = Scenario::chapter();
  if (!opts.model_path.empty()) {
    s.scene = opts.model_path;
    s.name = std::filesystem::path(opts.model_path).stem().string();
    s.timestep.reset();  // the scene's own
  }
  if (!opts.ctrls.empty()) {
    s.controls.clear();
    for (const auto& [actuator, value] : opts.ctrls) s.controls.push_back({actuator, {{When::steps(0), value}}});
  } else if (!opts.model_path.empty()) {
    s.controls.clear();
    if (scene != nullptr && scene->get()->nu > 0) s.controls.push_back({"0", {{When::steps(0), 1.0}}});
  }
  if (!opts.body.empty()) {
    s.disturbances[0].body = opts.body;
  } else if (!opts.model_path.empty()) {
    s.disturbances.clear();  // another scene: no shove unless --body names what to shove
  }
  // Record what moves freely, what is pushed (by name, or by index when the
  // scene left it unnamed), and every actuator.
  s.record = RecordSpec{};
  if (scene != nullptr) {
    const mjModel* m = scene->get();
    const std::string pushed = s.disturbances.empty() ? std::string() : s.disturbances[0].body;
    for (int b = 1; b < m->nbody; ++b) {
      const char* name = mj_id2name(m, mjOBJ_BODY, b);
      const std::string id = name != nullptr && *name != '\0' ? std::string(name) : std::to_string(b);
      const bool free = m->body_jntnum[b] >= 1 && m->jnt_type[m->body_jntadr[b]] == mjJNT_FREE;
      if (free || id == pushed || (name != nullptr && *name != '\0' && std::to_string(b) == pushed)) {
        s.record.bodies.push_back(id);
      }
    }
    for (int a = 0; a < m->nu; ++a) s.record.actuators.push_back(std::to_string(a));
  }
  return s;
}

namespace {

// A scenario's bad name, in the words of the flags that gave it: the quick
// flags' scenario has the shove as disturbance[0] (--body) and the --ctrl
// values as control[0], control[1]...
std::string scenario_error(const Options& opts, const std::string& what) {
  if (!opts.scenario_path.empty()) return "--scenario " + opts.scenario_path + ": " + what;
  const std::string shove = "disturbance[0]: ";
  if (what.rfind(shove, 0) == 0) {
    return "--body" + std::string(opts.body.empty() ? " (default box)" : "") + ": " + what.substr(shove.size());
  }
  if (what.rfind("control[", 0) == 0 && what.find("]: ") != std::string::npos) {
    const size_t index = std::strtoul(what.c_str() + 8, nullptr, 10);
    const size_t rest = what.find("]: ") + 3;
    if (index < opts.ctrls.size()) return "--ctrl " + opts.ctrls[index].first + ": " + what.substr(rest);
    return "actuator 0 (the chapter's ctrl; choose with --ctrl): " + what.substr(rest);
  }
  return what;
}

}  // namespace

void check_run_inputs(Options& opts, const Model& scene, const Scenario* scenario) {
  if (scenario != nullptr) {
    try {
      check_scenario(scene, *scenario, scenario_config(opts));
    } catch (const Error& e) {
      throw UsageError(scenario_error(opts, e.what()));
    }
    if (opts.command == Command::kSweep) complete_scenario_sweep(opts, scene, *scenario);
    return;
  }
  if (!scene.has_chapter_layout()) {
    throw UsageError("--model: " + scene.missing_layout() +
                     "; for any other scene, name the body to shove (--body) or run a --scenario");
  }
  if (!opts.model_path.empty() && !opts.timestep_given) opts.run.timestep = scene.timestep();  // the scene's own
}

void complete_scenario_sweep(Options& opts, const Model& scene, const Scenario& scenario) {
  const char* flag = opts.sweep_duration_given ? "--duration" : "--duration (default: the scenario's length)";
  if (!opts.sweep_duration_given) {
    try {
      opts.sweep_duration = scenario_duration(scene, scenario);
    } catch (const Error& e) {
      throw UsageError(scenario_error(opts, e.what()));
    }
  }
  std::string timesteps_flag = std::string(opts.sweep_timesteps.empty() ? "" : "--timesteps/") + flag;
  if (opts.sweep_timesteps.empty()) {
    opts.sweep_timesteps = default_scenario_sweep_timesteps(opts.sweep_duration);
    if (opts.sweep_timesteps.empty()) {
      throw UsageError(std::string(flag) + ": " + python_float_repr(opts.sweep_duration) +
                       " s of sim time is too short for any of the default timesteps (each run needs " +
                       std::to_string(kMinSweepSteps) + " steps); give --duration or --timesteps");
    }
  }
  for (const double dt : opts.sweep_timesteps) {
    try {
      (void)sweep_steps(opts.sweep_duration, dt);
    } catch (const std::exception& e) {
      throw UsageError(timesteps_flag + ": " + e.what());
    }
  }
}

ScenarioConfig scenario_config(const Options& opts) {
  ScenarioConfig c;
  c.seed = opts.run.seed;
  c.rng = opts.run.rng;
  if (opts.timestep_given) c.timestep = opts.run.timestep;
  if (opts.steps_given) c.steps = opts.run.num_steps();
  c.perturb = opts.run.perturb;
  c.record_every = opts.run.record_every;
  return c;
}

std::string help_text(std::string_view program, std::string_view recording) {
  std::string text = "usage: " + std::string(program) + R"( [options]

The chapter's MuJoCo simulation loop (ch0.1-sim-loop): a box on a floor, a
pusher on a slide joint at full throttle, and a seeded sideways shove on the
box halfway through. Writes metrics.json and trajectory.csv into --out.

options:
  --seed N          seeds the shove direction and strength (0 .. 2^64-1; default 0)
  --rng NAME        the generator that draws the shove: mt19937_64 (default,
                    std::mt19937_64) or numpy (the chapter's
                    np.random.default_rng(seed), PCG64; numpy not needed)
  --steps N         steps to run (default 2000)
  --timestep S      sim seconds per mj_step (default 0.002; 0.05 breaks it)
  --smoke           fixed 300-step run for CI; two runs match byte for byte
  --out DIR         output directory (default outputs/ch0.1-sim-loop)
  --no-perturb      skip the shove: the baseline run
  --plot            also draw trajectory.png (x of the pusher and the box, box
                    y and z, contacts; the shove shaded), with matplotlib
                    through the Python package
  --energy-audit    account for every joule: energy and work columns in
                    trajectory.csv, totals in the summary
  --record-every K  write every K-th step to trajectory.csv (default 1; the
                    final state is always written)
  --model FILE      another MJCF scene, at its own timestep unless --timestep
                    is given (default: the chapter's pusher scene). Alone it
                    runs the chapter's loop: a body "box" on a free joint and
                    an actuator 0 on a slide or hinge joint
  --body BODY       the body (a name or an index) the chapter's shove acts on
                    (default box; on a --model scene, no shove unless given):
                    runs a scenario on any scene (see below)
  --ctrl ACT=VALUE  drive actuator ACT (a name or an index) at VALUE, held
                    for the whole run; repeatable (default: actuator 0 at 1.0)
  --scenario FILE   a scenario file (TOML): the scene, timestep, length,
                    controls, disturbances and recording, as data
  --rerun, --no-rerun
                    )";
  text += recording;
  text += R"(
  --version         print the version and exit
  -h, --help        print this help and exit

commands:
  sweep             the baseline at many timesteps: where Break It begins
                    (see sweep --help)

scenarios: with --scenario, --body or --ctrl, trajectory.csv has columns named
from the scene (a row per step: the ctrl applied, the forces, each recorded
body's pose and velocity, joints, actuator forces, sensors, contacts) and
metrics.json the scenario's figures; --steps, --timestep, --seed, --rng,
--no-perturb, --smoke and --record-every still apply.

exit status: 0 done, 1 the run failed (MuJoCo error, cannot write outputs),
2 bad command line or input (a flag's value, --model, --scenario, --out).
)";
  return text;
}

std::string sweep_help_text(std::string_view program) {
  return "usage: " + std::string(program) + R"( sweep [options]

Runs the baseline (no shove) at many timesteps over the same span of sim time,
in parallel over one compiled model, with the energy audit on; prints a table,
names the largest stable timestep, and writes sweep.csv into --out.

A timestep is stable when the box's centre never rises more than 5 mm above
its resting height (0.05 m), does not end more than 1 mm below it, and MuJoCo
raised no warning. The largest stable timestep is the largest one below which
every swept timestep is stable.

options:
  --timesteps A,B,...   the timesteps to run (default: 25 round ones, 1, 2, 3,
                        4, 5, 6 and 8 per decade, from 0.0005 to 1)
  --range FROM:TO:N     N timesteps from FROM to TO, log-spaced
  --duration S          sim seconds per run (default 4)
  --threads N           workers (default: one per core)
  --out DIR             output directory (default outputs/ch0.1-sim-loop)
  --model FILE          another MJCF scene (as for the run)
  --plot                also draw sweep.png, with matplotlib through the
                        Python package
  -h, --help            print this help and exit

scenario sweeps: --scenario FILE (or --body NAME, --ctrl ACT=VALUE, with or
without --model, as for a run) sweeps the scenario instead: each timestep runs
it over --duration (default: the scenario's own length) with its controls and
disturbances (seed 0), and the finest timestep is the reference. A timestep
blew up when MuJoCo or simloop_DIVERGED warned, or a recorded body ended more
than 10% of the scene's size (MuJoCo's stat.extent) from where the reference
left it. The default grid drops timesteps that leave a run under 4 steps.
)";
}

}  // namespace simloop::cli
