// python -m simloop's `batch` flags (parse_batch): each value checked as far
// as the flags alone allow, refused in one line beginning "batch: " that
// names the flag and the value. The scene's checks (names, values, --rng,
// the timesteps' range) follow once the scenario is loaded.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cli_options.hpp"
#include "simloop/errors.hpp"

namespace simloop::cli {
namespace {

// Wide enough for a range's end past the last seed (2^64) and for a sum of
// counts: the limits are checked on exact numbers, before any overflow.
__extension__ using Wide = unsigned __int128;
constexpr Wide kLastSeed = std::numeric_limits<std::uint64_t>::max();

UsageError usage(const std::string& message) { return UsageError("batch: " + message); }

std::string text(Wide n) {
  std::string digits;
  do {
    digits.insert(digits.begin(), static_cast<char>('0' + static_cast<int>(n % 10)));
    n /= 10;
  } while (n != 0);
  return digits;
}

// ASCII digits (not '²', which Python's isdigit takes), held at 10^38 past
// that: far beyond any seed, so a limit still refuses it.
std::optional<Wide> whole(std::string_view s) {
  if (s.empty()) return std::nullopt;
  Wide cap = 1;
  for (int i = 0; i < 38; ++i) cap *= 10;
  Wide n = 0;
  for (const char c : s) {
    if (c < '0' || c > '9') return std::nullopt;
    n = n > cap / 10 ? cap : std::min(cap, n * 10 + static_cast<unsigned>(c - '0'));
  }
  return n;
}

// N, A:B (A to B-1) and A:B:STEP, joined by commas; at most kMaxBatchRuns
// seeds, counted before any is listed.
std::vector<SeedRange> parse_seeds(std::string_view value) {
  std::vector<SeedRange> ranges;
  Wide count = 0;
  for (const std::string_view part : split(value, ',')) {
    const std::vector<std::string_view> fields = split(part, ':');
    std::vector<Wide> n;
    for (const std::string_view field : fields) {
      if (const std::optional<Wide> number = whole(field)) n.push_back(*number);
    }
    if (n.size() != fields.size() || n.size() > 3) {
      throw usage("--seeds: " + quoted_value(value) +
                  " is not seeds (N, A:B for A to B-1, A:B:STEP, joined by commas)");
    }
    Wide last = n[0];
    Wide step = 1;
    if (n.size() > 1) {
      step = n.size() == 3 ? n[2] : 1;
      if (step == 0 || n[1] <= n[0]) {
        throw usage("--seeds: " + quoted_value(part) + " is an empty range (A:B runs A to B-1)");
      }
      last = n[0] + (n[1] - 1 - n[0]) / step * step;
    }
    if (last > kLastSeed) throw usage("--seeds: " + quoted_value(value) + ": seeds go from 0 to 2^64-1");
    // A step past the last seed leaves the range its first seed alone.
    ranges.push_back({static_cast<std::uint64_t>(n[0]), static_cast<std::uint64_t>(last),
                      static_cast<std::uint64_t>(std::min(step, kLastSeed))});
    count += (last - n[0]) / step + 1;
  }
  if (count > kMaxBatchRuns) {
    throw usage("--seeds: " + quoted_value(value) + " is " + text(count) + " seeds; a batch runs at most " +
                std::to_string(kMaxBatchRuns) + " (split it)");
  }
  return ranges;
}

bool names_a_non_finite(std::string s) {
  if (!s.empty() && (s[0] == '-' || s[0] == '+')) s.erase(0, 1);
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s == "inf" || s == "infinity" || s == "nan";
}

// Values joined by commas, each a finite plain decimal; their range is the library's.
std::vector<double> parse_numbers(const std::string& flag, std::string_view value) {
  std::vector<double> values;
  for (const std::string_view item : split(value, ',')) {
    const std::string s(item);
    const bool plain = plain_decimal(s);
    if (!plain && !names_a_non_finite(s)) {
      throw usage(flag + ": " + quoted_value(item) + " is not a number (values are joined by commas)");
    }
    const double x = plain ? std::strtod(s.c_str(), nullptr) : HUGE_VAL;
    if (!std::isfinite(x)) throw usage(flag + ": " + quoted_value(item) + " is not a finite number");
    values.push_back(x);
  }
  return values;
}

// --friction [GEOM=]V,..., --mass BODY=V,..., --damping [JOINT=]V,...,
// --gravity G,...: an axis of the grid, each kind and name once.
void add_param(BatchOptions& batch, const std::string& flag, std::string_view value) {
  const std::string kind = flag.substr(2);
  const size_t eq = value.rfind('=');
  const bool has_name = eq != std::string_view::npos;
  const std::string name(has_name ? value.substr(0, eq) : std::string_view());
  if (kind == "mass" && !has_name)
    throw usage("--mass: " + quoted_value(value) + " needs a body: --mass BODY=KG,KG,...");
  if (kind == "gravity" && has_name) {
    throw usage("--gravity: " + quoted_value(value) +
                ": gravity is the whole scene's, give values only: --gravity G,G,...");
  }
  if (has_name && name.empty()) throw usage(flag + ": " + quoted_value(value) + " has an empty name before '='");
  for (const BatchParam& p : batch.params) {
    if (p.kind == kind && p.name == name) {
      throw usage(flag + ": " + quoted_value(value) + ": " + kind + " of " +
                  (name.empty() ? std::string("everything") : quoted_value(name)) + " is given twice");
    }
  }
  batch.params.push_back({kind, name, parse_numbers(flag, has_name ? value.substr(eq + 1) : value)});
}

std::int64_t parse_count(const std::string& flag, std::string_view value, std::int64_t most) {
  const std::optional<Wide> n = whole(value);
  if (!n || *n < 1 || *n > static_cast<Wide>(most)) {
    throw usage(flag + ": " + quoted_value(value) + " is not a whole number from 1 to " + std::to_string(most));
  }
  return static_cast<std::int64_t>(*n);
}

}  // namespace

Options parse_batch(int argc, const char* const* argv) {
  static constexpr std::string_view kWithValue[] = {
      "--scenario", "--seeds", "--timestep",  "--friction", "--mass",       "--damping", "--gravity",
      "--steps",    "--rng",   "--scheduler", "--threads",  "--chunk-size", "--out"};
  Options opts;
  opts.command = Command::kBatch;
  BatchOptions& batch = opts.batch;
  for (int i = 2; i < argc; ++i) {
    const std::string_view arg = argv[i];
    std::string_view flag = arg;
    std::optional<std::string_view> inline_value;
    if (const size_t eq = arg.find('='); arg.rfind("--", 0) == 0 && eq != std::string_view::npos) {
      flag = arg.substr(0, eq);
      inline_value = arg.substr(eq + 1);
    }
    if (flag == "--resume" || flag == "--no-perturb" || flag == "--help" || flag == "-h") {
      if (inline_value) throw usage(std::string(flag) + " takes no value, got " + quoted_value(arg));
      if (flag == "--resume") {
        batch.resume = true;
      } else if (flag == "--no-perturb") {
        batch.perturb = false;
      } else {
        opts.help = true;
      }
      continue;
    }
    if (std::find(std::begin(kWithValue), std::end(kWithValue), flag) == std::end(kWithValue)) {
      throw usage("unknown argument " + quoted_value(arg) + " (see batch --help)");
    }
    if (!inline_value && i + 1 >= argc) throw usage(std::string(flag) + " needs a value");
    const std::string_view value = inline_value ? *inline_value : std::string_view(argv[++i]);
    const std::string name(flag);
    if (flag == "--scenario" || flag == "--out") {
      if (value.empty()) throw usage(name + ": '' names no file");
      if (flag == "--out") {
        batch.out = std::string(value);
      } else {
        batch.scenario = std::string(value);
      }
    } else if (flag == "--seeds") {
      batch.seeds = parse_seeds(value);
    } else if (flag == "--timestep") {
      batch.timesteps = parse_numbers(name, value);
    } else if (flag == "--steps") {
      batch.steps = parse_count(name, value, kMaxSteps);
    } else if (flag == "--threads") {
      batch.threads = static_cast<int>(parse_count(name, value, kMaxThreads));
    } else if (flag == "--chunk-size") {
      batch.chunk_size = parse_count(name, value, kMaxChunkRuns);
    } else if (flag == "--rng") {
      batch.rng = std::string(value);
    } else if (flag == "--scheduler") {
      batch.scheduler = std::string(value);
    } else {
      add_param(batch, name, value);
    }
  }
  return opts;
}

}  // namespace simloop::cli
