// What the binding files share: long C++ work that Ctrl-C can stop
// (Interruptible), rows handed to Python as a run makes them (RowsToPython),
// and the standard library's resource failures said with what was being done.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cstdint>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "simloop/control.hpp"
#include "simloop/run.hpp"

namespace simloop_py {

namespace py = pybind11;

// The standard library's resource failures, said with what was being done
// (pybind11 alone would say "std::bad_alloc"). Raised as MemoryError and
// RuntimeError.
class OutOfMemory : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
class ResourceFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

template <class Work>
auto naming_failures(const std::string& what, Work&& work) -> decltype(work()) {
  try {
    return work();
  } catch (const std::bad_alloc&) {
    throw OutOfMemory(what + ": out of memory");
  } catch (const std::system_error& e) {
    throw ResourceFailure(what + ": " + e.what());
  }
}


// Long C++ work that Ctrl-C can stop. The work runs with the GIL released;
// between its chunks of steps the RunControl polls (on this thread, at most
// every 20 ms): the poll takes the GIL, runs Python's signal handlers
// (PyErr_CheckSignals) and the caller's progress(steps_done, steps_total).
// If either raises, the poll keeps that Python exception and requests a
// stop; the loop throws simloop::Interrupted at its next chunk, and the
// kept exception (KeyboardInterrupt, say) is what the caller sees. Python
// runs signal handlers only on the main thread, so elsewhere, without a
// progress callback, there is nothing to poll and the GIL is left alone.
class Interruptible {
 public:
  explicit Interruptible(py::object progress)
      : progress_(progress.is_none() ? py::object() : std::move(progress)),
        control_(progress_ || on_main_thread() ? simloop::RunControl::Poll(
                                                     [this](std::int64_t done, std::int64_t total) { poll(done, total); })
                                               : simloop::RunControl::Poll()) {}

  template <class Work>
  auto run(Work&& work) -> decltype(work(static_cast<simloop::RunControl*>(nullptr))) {
    try {
      py::gil_scoped_release release;
      return work(&control_);
    } catch (...) {
      // Interrupted, normally; whatever ended the work, a Ctrl-C the user
      // pressed (or progress's exception) is what they hear about.
      if (!error_) throw;
      py::error_already_set error = std::move(*error_);
      error_.reset();
      throw error;
    }
  }

  // After the work is done: one last progress call, at its full count.
  void finish() {
    if (progress_) progress_(control_.steps_done(), control_.steps_total());
  }

 private:
  static bool on_main_thread() {
    return py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>() ==
           PyThread_get_thread_ident();
  }

  void poll(std::int64_t done, std::int64_t total) noexcept {
    if (control_.stop_requested()) return;
    py::gil_scoped_acquire gil;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (progress_) progress_(done, total);
    } catch (py::error_already_set& e) {
      error_.emplace(std::move(e));
      control_.request_stop();
    } catch (...) {
      // Not from Python (a bad_alloc, say): stop; the caller sees Interrupted.
      control_.request_stop();
    }
  }

  py::object progress_;
  std::optional<py::error_already_set> error_;
  simloop::RunControl control_;
};


// The rows of a run handed to Python as they come (for a recording made
// while the run streams its files): `to.columns(names)` once, then
// `to.rows(array)` per block, each a (rows, columns) float64 copy, and
// `to.finish(result)` once the run is done (before its outputs are put in
// place), called with the GIL. An exception there stops the run and reaches
// the caller (raise_if_failed, once the run is over).
class RowsToPython final : public simloop::RowSink {
 public:
  struct Failed {};
  explicit RowsToPython(py::object to) : to_(std::move(to)) {}
  ~RowsToPython() override {
    py::gil_scoped_acquire gil;
    to_ = py::object();
    error_.reset();
  }
  void describe(const std::vector<simloop::Column>& columns) override {
    call([&] {
      py::list names;
      for (const simloop::Column& c : columns) names.append(c.name);
      to_.attr("columns")(names);
    });
  }
  void start(int columns, std::int64_t /*rows*/) override { columns_ = columns; }
  void write(const double* rows, std::int64_t count) override {
    call([&] {
      py::array_t<double> block({static_cast<py::ssize_t>(count), static_cast<py::ssize_t>(columns_)});
      std::copy(rows, rows + count * columns_, block.mutable_data());
      to_.attr("rows")(block);
    });
  }
  template <class Result>
  void finish(const Result& result) {
    call([&] { to_.attr("finish")(py::cast(result)); });
  }
  void raise_if_failed() {
    if (!error_) return;
    py::error_already_set error = std::move(*error_);
    error_.reset();
    throw error;
  }

 private:
  template <class Call>
  void call(Call&& c) {
    py::gil_scoped_acquire gil;
    try {
      c();
    } catch (py::error_already_set& e) {
      error_.emplace(std::move(e));
      throw Failed{};
    }
  }
  py::object to_;
  int columns_ = 0;
  std::optional<py::error_already_set> error_;
};


}  // namespace simloop_py
