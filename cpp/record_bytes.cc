#include "simloop/record_bytes.hpp"

#include <array>
#include <cstring>
#include <type_traits>
#include <utility>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/scene_params.hpp"

namespace simloop {
namespace {

// What the bytes hold, after the version: a RunResult's bytes read as a
// RunRecord (or the other way) are refused by name, not misread.
enum class Kind : std::uint8_t { kRecord = 1, kRunResult = 2, kSweep = 3 };

const char* kind_name(Kind kind) {
  switch (kind) {
    case Kind::kRecord:
      return "ScenarioResult";
    case Kind::kRunResult:
      return "RunResult";
    case Kind::kSweep:
      return "SweepResult";
  }
  return nullptr;
}

// Each struct's fields, in order: one list serves both directions, Writer's
// io(...) appending and Reader's reading back. Io::Of<T> is const T& for
// the Writer and T& for the Reader.
template <class Io>
void fields(Io& io, typename Io::template Of<Warning> w) {
  io(w.name, w.count, w.first_step, w.message);
}
template <class Io>
void fields(Io& io, typename Io::template Of<Column> c) {
  io(c.name, c.unit, c.integer, c.input, c.body);
}
template <class Io>
void fields(Io& io, typename Io::template Of<Schedule::ControlChange> c) {
  io(c.step, c.actuator, c.value);
}
template <class Io>
void fields(Io& io, typename Io::template Of<Schedule::Force> f) {
  io(f.body, f.wrench, f.start, f.end, f.asked_end);
}
template <class Io>
void fields(Io& io, typename Io::template Of<Metrics> m) {
  io(m.steps, m.seed, m.perturb, m.box_final_pos, m.box_final_speed, m.pusher_final_x, m.lateral_drift,
     m.shove_moved_box);
}
template <class Io>
void fields(Io& io, typename Io::template Of<Shove> s) {
  io(s.newtons, s.sign, s.start_step, s.num_steps, s.rng);
}
template <class Io>
void fields(Io& io, typename Io::template Of<EnergyTotals> e) {
  io(e.energy_start, e.energy_end, e.work_actuator, e.work_shove, e.work_passive, e.work_constraint,
     e.work_constraint_positive, e.unexplained);
}
template <class Io>
void fields(Io& io, typename Io::template Of<RunConfig> c) {
  io(c.seed, c.steps, c.timestep, c.perturb, c.smoke, c.record_every, c.audit_energy, c.rng);
}
// A sweep point as measured: stable is judged again on reading.
template <class Io>
void fields(Io& io, typename Io::template Of<SweepPoint> p) {
  io(p.timestep, p.steps, p.peak_box_z, p.max_abs_box_y, p.final_box_x, p.final_box_y, p.final_box_z, p.final_pusher_x,
     p.warnings, p.energy);
}
template <class Io>
void fields(Io& io, typename Io::template Of<SweepResult> r) {
  io(r.duration, r.points);
}

template <class Io>
void fields(Io& io, typename Io::template Of<SceneParam> p) {
  io(p.kind, p.name, p.value, p.field, p.index);
}
template <class Io>
void fields(Io& io, typename Io::template Of<Schedule::Start::MocapPos> g) {
  io(g.mocap, g.body, g.pos);
}
// What the start drew: a result that travels (an executor's, a pickle) keeps its table's columns.
template <class Io>
void fields(Io& io, typename Io::template Of<Schedule::Start> s) {
  io(s.qpos, s.qvel, s.params, s.keyframe, s.goals);
}

template <class Io>
void fields(Io& io, typename Io::template Of<RunRecord> r) {
  io(r.name, r.seed, r.rng, r.perturb, r.disturbed_bodies, r.columns, r.final_row, r.final_state, r.trajectory, r.rows,
     r.schedule.steps, r.schedule.control_changes, r.schedule.forces, r.schedule.start, r.warnings, r.timestep,
     r.sim_time, r.energy);
}
template <class Io>
void fields(Io& io, typename Io::template Of<RunResult> r) {
  fields(io, static_cast<typename Io::template Of<RunRecord>>(r));  // the record's, then the report's
  io(r.config, r.metrics, r.unrounded_metrics, r.shove);
}

// Numbers as their bytes; bools and enums as one byte (a bool's other bit
// patterns are not bools); vectors and strings as a uint64 count, then
// their elements.
class Writer {
 public:
  template <class T>
  using Of = const T&;
  template <class... T>
  void operator()(const T&... values) {
    (field(values), ...);
  }

  explicit Writer(Kind kind) {
    field(kRecordBytesVersion);
    field(static_cast<std::uint8_t>(kind));
  }
  template <class T>
  void field(const T& value) {
    if constexpr (std::is_same_v<T, bool> || std::is_enum_v<T>) {
      field(static_cast<std::uint8_t>(value));
    } else if constexpr (std::is_arithmetic_v<T>) {
      raw(&value, sizeof value);
    } else {
      fields(*this, value);
    }
  }
  template <class T, std::size_t N>
  void field(const std::array<T, N>& values) {
    for (const T& v : values) field(v);
  }
  template <class T>
  void field(const std::vector<T>& values) {
    field(static_cast<std::uint64_t>(values.size()));
    if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
      raw(values.data(), values.size() * sizeof(T));
    } else {
      for (const T& v : values) field(v);
    }
  }
  void field(const std::string& text) {
    field(static_cast<std::uint64_t>(text.size()));
    bytes_ += text;
  }
  void field(const Trajectory& t) {
    field(t.rows());
    field(t.columns());
    raw(t.data(), static_cast<size_t>(t.rows()) * static_cast<size_t>(t.columns()) * sizeof(double));
  }
  [[nodiscard]] std::string bytes() && { return std::move(bytes_); }

 private:
  void raw(const void* data, size_t n) { bytes_.append(static_cast<const char*>(data), n); }
  std::string bytes_;
};

// The largest byte a bool or an enum of the fields may hold.
template <class T>
constexpr std::uint8_t largest() {
  static_assert(std::is_same_v<T, bool> || std::is_same_v<T, ShoveRng> || std::is_same_v<T, SceneParam::Kind>,
                "give the new enum's largest value here");
  if constexpr (std::is_same_v<T, ShoveRng>) return static_cast<std::uint8_t>(ShoveRng::kNumpy);
  if constexpr (std::is_same_v<T, SceneParam::Kind>) return static_cast<std::uint8_t>(SceneParam::Kind::kModel);
  return 1;
}

class Reader {
 public:
  template <class T>
  using Of = T&;
  template <class... T>
  void operator()(T&... values) {
    (field(values), ...);
  }

  Reader(std::string_view bytes, Kind kind) : bytes_(bytes), what_(kind_name(kind)) {
    std::uint32_t version = 0;
    field(version);
    if (version != kRecordBytesVersion) {
      throw InvalidArgument(std::string("cannot unpickle a ") + what_ + " pickled by another simloop version (format " +
                            std::to_string(version) + "; this one reads " + std::to_string(kRecordBytesVersion) + ")");
    }
    std::uint8_t held = 0;
    field(held);
    if (held != static_cast<std::uint8_t>(kind)) {
      const char* other = kind_name(static_cast<Kind>(held));
      if (other == nullptr) fail();
      throw InvalidArgument(std::string("cannot unpickle a ") + what_ + ": the saved fields are a " + other + "'s");
    }
  }
  template <class T>
  void field(T& value) {
    if constexpr (std::is_same_v<T, bool> || std::is_enum_v<T>) {
      std::uint8_t byte = 0;
      field(byte);
      if (byte > largest<T>()) fail();
      value = static_cast<T>(byte);
    } else if constexpr (std::is_arithmetic_v<T>) {
      std::memcpy(&value, take(sizeof value), sizeof value);
    } else {
      fields(*this, value);
    }
  }
  template <class T, std::size_t N>
  void field(std::array<T, N>& values) {
    for (T& v : values) field(v);
  }
  template <class T>
  void field(std::vector<T>& values) {
    if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
      values.resize(count(sizeof(T)));
      const size_t n = values.size() * sizeof(T);
      if (n > 0) std::memcpy(values.data(), take(n), n);
    } else {
      values.resize(count(8));  // every element written holds at least 8 bytes (a count, an int64)
      for (T& v : values) field(v);
    }
  }
  void field(std::string& text) {
    const size_t n = count(1);
    text.assign(take(n), n);
  }
  void field(Trajectory& t) {
    std::int64_t rows = 0;
    int columns = 0;
    field(rows);
    field(columns);
    if (rows < 0 || columns < 0 ||
        (columns > 0 &&
         static_cast<std::uint64_t>(rows) > left() / sizeof(double) / static_cast<std::uint64_t>(columns))) {
      fail();
    }
    t = Trajectory(rows, columns);
    const size_t n = static_cast<size_t>(rows) * static_cast<size_t>(columns) * sizeof(double);
    if (n > 0) std::memcpy(t.mutable_row(0), take(n), n);
  }
  // All the bytes read, and what the bindings index by agrees: a force per
  // disturbed body, a name per trajectory column.
  void finish(const RunRecord& r) const {
    if (left() != 0 || r.disturbed_bodies.size() != r.schedule.forces.size() ||
        static_cast<size_t>(r.trajectory.columns()) > r.columns.size()) {
      fail();
    }
  }
  void finish(const SweepResult& /*result*/) const {
    if (left() != 0) fail();
  }

 private:
  [[nodiscard]] std::uint64_t left() const noexcept { return bytes_.size() - at_; }
  // A stored element count, checked against the bytes left (each element
  // takes at least `min_size` bytes), so bad bytes cannot ask for huge memory.
  size_t count(size_t min_size) {
    std::uint64_t n = 0;
    field(n);
    if (n > left() / min_size) fail();
    return static_cast<size_t>(n);
  }
  const char* take(size_t n) {
    if (n > left()) fail();
    const char* at = bytes_.data() + at_;
    at_ += n;
    return at;
  }
  [[noreturn]] void fail() const {
    throw InvalidArgument(std::string("cannot unpickle a ") + what_ +
                          ": the saved fields are damaged or from another simloop version");
  }
  std::string_view bytes_;
  const char* what_;
  size_t at_ = 0;
};

template <class Result>
std::string write(const Result& result, Kind kind) {
  Writer out(kind);
  fields(out, result);
  return std::move(out).bytes();
}

template <class Result>
Result read(std::string_view bytes, Kind kind) {
  Reader in(bytes, kind);
  Result result;
  fields(in, result);
  in.finish(result);
  return result;
}

}  // namespace

std::string to_bytes(const RunRecord& record) { return write(record, Kind::kRecord); }
std::string to_bytes(const RunResult& result) { return write(result, Kind::kRunResult); }
std::string to_bytes(const SweepResult& result) { return write(result, Kind::kSweep); }

RunRecord record_from_bytes(std::string_view bytes) { return read<RunRecord>(bytes, Kind::kRecord); }
RunResult run_result_from_bytes(std::string_view bytes) { return read<RunResult>(bytes, Kind::kRunResult); }

SweepResult sweep_result_from_bytes(std::string_view bytes) {
  SweepResult result = read<SweepResult>(bytes, Kind::kSweep);
  judge_sweep(result);
  return result;
}

}  // namespace simloop
