#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <sstream>

#include "simloop/errors.hpp"
#include "simloop/rows.hpp"

namespace simloop {
namespace {

// "1.6 TiB": a byte count for people.
std::string human_bytes(std::uint64_t bytes) {
  static constexpr const char* kUnits[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double value = static_cast<double>(bytes);
  int unit = 0;
  while (value >= 1024.0 && unit < 6) {
    value /= 1024.0;
    ++unit;
  }
  char text[32];
  if (unit == 0) {
    std::snprintf(text, sizeof text, "%llu bytes", static_cast<unsigned long long>(bytes));
  } else {
    std::snprintf(text, sizeof text, "%.1f %s", value, kUnits[unit]);
  }
  return text;
}

// The cgroup (v2) memory limit at /sys/fs/cgroup (a container's own limit),
// or UINT64_MAX if none.
std::uint64_t cgroup_memory_max() noexcept {
  std::FILE* f = std::fopen("/sys/fs/cgroup/memory.max", "r");
  if (f == nullptr) return std::numeric_limits<std::uint64_t>::max();
  unsigned long long limit = 0;
  const bool numeric = std::fscanf(f, "%llu", &limit) == 1;  // "max" when unlimited
  std::fclose(f);
  return numeric && limit > 0 ? limit : std::numeric_limits<std::uint64_t>::max();
}

}  // namespace

std::uint64_t trajectory_memory_budget() noexcept {
  std::uint64_t limit = std::numeric_limits<std::uint64_t>::max();
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page_size = ::sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page_size > 0) {
    limit = static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size);
  }
  limit = std::min(limit, cgroup_memory_max());
  for (const int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    struct rlimit rl {};
    if (::getrlimit(resource, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
      limit = std::min<std::uint64_t>(limit, rl.rlim_cur);
    }
  }
  return limit / 2;
}

std::uint64_t KeptRows::bytes() const noexcept {
  const auto rows = static_cast<std::uint64_t>(Trajectory::rows_for(steps, record_every));
  const std::uint64_t row_bytes = sizeof(double) * static_cast<std::uint64_t>(columns);
  constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();
  return rows > kMax / row_bytes ? kMax : rows * row_bytes;
}

void check_kept_rows(const std::vector<KeptRows>& runs, std::uint64_t budget) {
  constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();
  std::uint64_t total = 0;
  std::size_t largest = 0;
  std::uint64_t largest_bytes = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const std::uint64_t bytes = runs[i].bytes();
    total = bytes > kMax - total ? kMax : total + bytes;
    if (bytes > largest_bytes) {
      largest = i;
      largest_bytes = bytes;
    }
  }
  if (total <= budget) return;
  const KeptRows& r = runs[largest];
  std::ostringstream msg;
  msg << "steps " << r.steps << " with record_every " << r.record_every;
  if (runs.size() == 1) {
    msg << " would keep " << human_bytes(total) << " of trajectory (" << r.columns << " columns) in memory";
  } else {
    msg << " (run " << largest << ", the largest of " << runs.size() << " runs) and the others would keep "
        << human_bytes(total) << " of trajectories in memory";
  }
  msg << " (at most " << human_bytes(budget) << " allowed: half of the machine's memory or the process's limit); "
      << (runs.size() == 1 ? "raise record_every, or let sim_loop stream it to a file" : "raise record_every");
  throw InvalidArgument(msg.str());
}

void check_threads(std::int64_t threads) {
  if (threads < 0 || threads > kMaxThreads) {
    throw InvalidArgument("threads must be from 1 to " + std::to_string(kMaxThreads) + ", or 0 for one per core, got " +
                          std::to_string(threads));
  }
}

}  // namespace simloop
