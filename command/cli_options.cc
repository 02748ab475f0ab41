// The commands' flags parsed (parse): each flag's value checked and refused
// in one line naming the flag and the value (UsageError).
#include "cli_options.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/sweep.hpp"

namespace simloop::cli {
namespace {

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
                     std::to_string(max) + ", got " + quoted_value(value));
  }
  return n;
}

double parse_timestep(std::string_view flag, std::string_view value) {
  const std::string text(value);
  const bool plain = plain_decimal(text);
  const double x = plain ? std::strtod(text.c_str(), nullptr) : 0.0;
  if (!plain || !std::isfinite(x) || !(x > 0.0)) {
    // 0.002s, 2ms: a number with a unit after it.
    const size_t unit = text.find_first_not_of("0123456789.");
    const std::string suffix = unit == std::string::npos ? std::string() : text.substr(unit);
    const bool has_unit =
        unit != 0 && !suffix.empty() && plain_decimal(text.substr(0, unit)) && suffix != "e" && suffix != "E" &&
        std::all_of(suffix.begin(), suffix.end(), [](unsigned char c) { return std::isalpha(c) != 0; });
    throw UsageError(std::string(flag) + " must be a positive, finite number of seconds" +
                     (has_unit ? " without a unit (0.002, not 0.002s)" : "") + ", got " + quoted_value(value));
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
    throw UsageError(std::string(flag) +
                     " must be ACTUATOR=VALUE (an actuator's name or index, a finite number), got " +
                     quoted_value(value));
  }
  return {std::string(value.substr(0, eq)), x};
}

std::vector<double> parse_timestep_list(std::string_view flag, std::string_view value) {
  std::vector<double> out;
  for (const std::string_view item : split(value, ',')) out.push_back(parse_timestep(flag, item));
  return out;
}

// FROM:TO:COUNT, log-spaced.
std::vector<double> parse_range(std::string_view flag, std::string_view value) {
  const size_t a = value.find(':');
  const size_t b = a == std::string_view::npos ? a : value.find(':', a + 1);
  if (b == std::string_view::npos) {
    throw UsageError(std::string(flag) + " must be FROM:TO:COUNT, got " + quoted_value(value));
  }
  const double from = parse_timestep(flag, value.substr(0, a));
  const double to = parse_timestep(flag, value.substr(a + 1, b - a - 1));
  const auto count = static_cast<int>(parse_u64(flag, value.substr(b + 1), 1, 10000));
  try {
    return log_spaced(from, to, count);
  } catch (const std::exception& e) {
    throw UsageError(std::string(flag) + ": " + e.what() + ", got " + quoted_value(value));
  }
}

// --video's file is a file of its own: not a folder or a device, and not
// one of the run's other outputs (the .png it falls back to included).
void check_video_file(const Options& opts) {
  if (opts.video.empty() || opts.help || opts.version) return;
  const std::string& given = opts.video.native();
  if (given.back() == '/' || !opts.video.has_stem() || opts.video.filename() == "..") {
    throw UsageError("--video must name a file, not a folder, got " + quoted_value(given));
  }
  const auto absolute = [](const std::filesystem::path& p) {
    std::error_code ignored;
    return std::filesystem::weakly_canonical(std::filesystem::absolute(p, ignored), ignored);
  };
  std::vector<std::pair<std::filesystem::path, std::string>> others = {{opts.out / "metrics.json", "metrics.json"},
                                                                       {opts.out / "trajectory.csv", "trajectory.csv"},
                                                                       {opts.out / "sim_loop.rrd", "recording"}};
  if (opts.plot) others.emplace_back(opts.out / "trajectory.png", "--plot's trajectory.png");
  for (const std::filesystem::path& file : {opts.video, std::filesystem::path(opts.video).replace_extension(".png")}) {
    std::error_code error;
    const std::filesystem::file_status status = std::filesystem::status(file, error);
    if (std::filesystem::is_directory(status)) {
      throw UsageError("--video: " + quoted_value(file.native()) + " is a folder; name a file in it");
    }
    if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
      throw UsageError("--video: " + quoted_value(file.native()) +
                       " is a device, a pipe or a socket, not a file it can write whole");
    }
    for (const auto& [other, what] : others) {
      if (absolute(file) == absolute(other)) {
        throw UsageError("--video: " + quoted_value(file.native()) + " is also the run's " + what +
                         "; name another file");
      }
    }
  }
}

// `plot trajectory|sweep [--out DIR] [--compare DIR ...] [--x auto|time|step]`:
// the chart python -m simloop draws from the CSV a run or sweep wrote.
Options parse_plot(int argc, const char* const* argv) {
  Options opts;
  opts.command = Command::kPlot;
  const std::string_view what = argc > 2 ? argv[2] : "";
  if (what == "-h" || what == "--help") {
    opts.help = true;
    return opts;
  }
  if (what != "trajectory" && what != "sweep")
    throw UsageError("plot needs 'trajectory' or 'sweep' first (see plot --help)");
  opts.plot_what = what;
  for (int i = 3; i < argc; ++i) {
    std::string_view flag = argv[i];
    std::string_view value;
    if (const auto eq = flag.find('='); flag.rfind("--", 0) == 0 && eq != std::string_view::npos) {
      value = flag.substr(eq + 1);
      flag = flag.substr(0, eq);
    }
    if (flag != "--out" && flag != "--compare" && flag != "--x") {
      throw UsageError("plot: unknown argument " + quoted_value(argv[i]) + " (see plot --help)");
    }
    if (value.empty()) {
      if (i + 1 >= argc) throw UsageError("plot: " + std::string(flag) + " needs a value");
      value = argv[++i];
    }
    if (flag == "--out") {
      opts.out = std::string(value);
    } else if (flag == "--compare") {
      opts.plot_compare.emplace_back(std::string(value));
    } else if (value != "auto" && value != "time" && value != "step") {
      throw UsageError("plot: --x must be auto, time or step, got " + quoted_value(value));
    } else {
      opts.plot_x = value;
    }
  }
  if (!opts.plot_compare.empty() && opts.plot_what != "trajectory") {
    throw UsageError("plot: --compare draws trajectories only");
  }
  return opts;
}

}  // namespace

std::vector<std::string_view> split(std::string_view s, char by) {
  std::vector<std::string_view> parts;
  for (size_t start = 0;;) {
    const size_t at = s.find(by, start);
    parts.push_back(s.substr(start, at == std::string_view::npos ? at : at - start));
    if (at == std::string_view::npos) return parts;
    start = at + 1;
  }
}

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

Options parse(const std::vector<std::string>& args) {
  std::vector<const char*> argv = {"simloop"};
  for (const std::string& a : args) argv.push_back(a.c_str());
  return parse(static_cast<int>(argv.size()), argv.data());
}

Options parse(int argc, const char* const* argv) {
  Options opts;
  const char* timesteps_flag = "--duration";  // what set the sweep's timesteps
  int first = 1;
  if (argc > 1 && std::string_view(argv[1]) == "plot") return parse_plot(argc, argv);
  if (argc > 1 && std::string_view(argv[1]) == "batch") return parse_batch(argc, argv);
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
      // A forgotten value must not swallow the next flag (--out --no-perturb
      // would run the shoved run into a folder named --no-perturb).
      if (const std::string_view next = argv[i + 1]; next.size() > 2 && next.rfind("--", 0) == 0) {
        throw UsageError(std::string(arg) + " needs a value, got the flag " + std::string(next) + " (write " +
                         std::string(arg) + "=" + std::string(next) + " for a value that begins with --)");
      }
      return argv[++i];
    };
    const auto no_value = [&] {
      if (inline_value) throw UsageError(std::string(arg) + " takes no value, got " + quoted_value(*inline_value));
    };
    const auto run_only = [&] {
      if (sweeping) throw UsageError(std::string(arg) + " is not a sweep option (see sweep --help)");
    };
    const auto sweep_only = [&] {
      if (!sweeping)
        throw UsageError(std::string(arg) + " belongs to the sweep command: sim_loop sweep " + std::string(arg));
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
        throw UsageError("--duration must be a positive, finite number of seconds, got " + quoted_value(v));
      }
    } else if (arg == "--threads") {
      sweep_only();
      opts.threads = static_cast<int>(parse_u64(arg, value(), 1, kMaxThreads));
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
      if (!rng) throw UsageError("--rng must be mt19937_64 or numpy, got " + quoted_value(v));
      opts.run.rng = *rng;
      opts.rng_given = true;
    } else if (arg == "--chapter") {
      run_only();
      no_value();
      opts.chapter = true;
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
    } else if (arg == "--video") {
      run_only();
      const std::string_view v = value();
      if (v.empty()) throw UsageError("--video must name a file (.mp4 or .png), got ''");
      opts.video = std::string(v);
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
      throw UsageError("unknown option " + quoted_value(arg) + " (see --help)");
    } else {
      throw UsageError("unexpected argument " + quoted_value(arg) + " (see --help)");
    }
  }
  if (opts.chapter) {  // the chapter draws its shove with numpy's default_rng
    if (opts.rng_given && opts.run.rng != ShoveRng::kNumpy) {
      throw UsageError(
          "--chapter draws the shove as the chapter does (--rng numpy); it cannot be combined with --rng " +
          std::string(rng_name(opts.run.rng)));
    }
    opts.run.rng = ShoveRng::kNumpy;
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
  check_video_file(opts);
  // The library would refuse it too; say it in the flags' words.
  try {
    validate(opts.run);
  } catch (const std::exception& e) {
    throw UsageError(std::string("--steps/--record-every: ") + e.what());
  }
  return opts;
}

}  // namespace simloop::cli
