// Pickling results: their fields, in order, as bytes, so every double comes
// back from a multiprocessing worker with the same bits.
#pragma once

#include <pybind11/pybind11.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "simloop/run_record.hpp"

namespace simloop_py {

namespace py = pybind11;
using simloop::Trajectory;

// A result's fields as bytes: plain values copied as they are. One list of
// fields per result (record_fields, chapter_result_fields) serves both
// directions: FieldWriter's field() appends, FieldReader's reads back.
class FieldWriter {
 public:
  template <class T>
  void field(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof value);
  }
  template <class T>
  void field(const std::vector<T>& values) {
    field(static_cast<std::uint64_t>(values.size()));
    if constexpr (std::is_trivially_copyable_v<T>) {
      bytes_.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
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
    bytes_.append(reinterpret_cast<const char*>(t.data()),
                  static_cast<size_t>(t.rows()) * static_cast<size_t>(t.columns()) * sizeof(double));
  }
  void field(const simloop::Warning& w) { warning_fields(*this, w); }
  void field(const simloop::Column& c) { column_fields(*this, c); }
  [[nodiscard]] py::bytes bytes() const { return py::bytes(bytes_); }

  template <class Io, class W>
  static void warning_fields(Io& io, W& w) {
    io.field(w.name);
    io.field(w.count);
    io.field(w.first_step);
    io.field(w.message);
  }
  template <class Io, class C>
  static void column_fields(Io& io, C& c) {
    io.field(c.name);
    io.field(c.unit);
    io.field(c.integer);
    io.field(c.input);
    io.field(c.body);
  }

 private:
  std::string bytes_;
};

class FieldReader {
 public:
  FieldReader(std::string bytes, const char* what) : bytes_(std::move(bytes)), what_(what) {}
  template <class T>
  void field(T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    std::memcpy(&value, take(sizeof value), sizeof value);
  }
  template <class T>
  void field(std::vector<T>& values) {
    if constexpr (std::is_trivially_copyable_v<T>) {
      values.resize(count(sizeof(T)));
      const size_t n = values.size() * sizeof(T);
      if (n > 0) std::memcpy(static_cast<void*>(values.data()), take(n), n);
    } else {
      values.resize(count(sizeof(std::uint64_t)));  // each element holds at least one count
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
    if (rows < 0 || columns < 0 || (columns > 0 && static_cast<std::uint64_t>(rows) > left() / sizeof(double) /
                                                       static_cast<std::uint64_t>(columns))) {
      fail();
    }
    t = Trajectory(rows, columns);
    const size_t n = static_cast<size_t>(rows) * static_cast<size_t>(columns) * sizeof(double);
    if (n > 0) std::memcpy(t.mutable_row(0), take(n), n);
  }
  void field(simloop::Warning& w) { FieldWriter::warning_fields(*this, w); }
  void field(simloop::Column& c) { FieldWriter::column_fields(*this, c); }
  void finish() const {
    if (at_ != bytes_.size()) fail();
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
    throw py::value_error(std::string("cannot unpickle a ") + what_ + ": the saved fields are damaged or from another "
                          "simloop version");
  }
  std::string bytes_;
  const char* what_;
  size_t at_ = 0;
};

// The pickle format's version: bump when a result's fields change.
constexpr int kPickleVersion = 3;

template <class Result, void (*Fields)(FieldWriter&, const Result&)>
py::tuple pickle_fields(const Result& r) {
  FieldWriter out;
  Fields(out, r);
  return py::make_tuple(kPickleVersion, out.bytes());
}

template <class Result, void (*Fields)(FieldReader&, Result&)>
Result unpickle_fields(const py::tuple& t, const char* what) {
  if (t.size() != 2 || t[0].cast<int>() != kPickleVersion) {
    throw py::value_error(std::string("cannot unpickle a ") + what + " pickled by another simloop version");
  }
  FieldReader in(t[1].cast<std::string>(), what);
  Result r;
  Fields(in, r);
  in.finish();
  return r;
}

// The fields of the record every run leaves (a chapter's RunResult adds its
// report's after them).
template <class Io, class Record>
void record_fields(Io& io, Record& r) {
  io.field(r.name);
  io.field(r.seed);
  io.field(r.rng);
  io.field(r.perturb);
  io.field(r.disturbed_bodies);
  io.field(r.columns);
  io.field(r.final_row);
  io.field(r.final_state);
  io.field(r.trajectory);
  io.field(r.rows);
  io.field(r.schedule.steps);
  io.field(r.schedule.control_changes);
  io.field(r.schedule.forces);
  io.field(r.warnings);
  io.field(r.timestep);
  io.field(r.sim_time);
}

// py::pickle for a result: Write and Read are its one list of fields.
template <class Result, void (*Write)(FieldWriter&, const Result&), void (*Read)(FieldReader&, Result&)>
auto pickling(const char* what) {
  return py::pickle(&pickle_fields<Result, Write>,
                    [what](const py::tuple& t) { return unpickle_fields<Result, Read>(t, what); });
}

}  // namespace simloop_py
