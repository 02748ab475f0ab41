// simloop._core, continued: the commands' outputs. The folder's lock
// (OutputLock), the recording's file (PipedFile) and its commit, and the
// signals the commands stop on.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "bindings_common.hpp"
#include "simloop/model.hpp"
#include "simloop/output.hpp"
#include "simloop/output_lock.hpp"
#include "simloop/piped_file.hpp"
#include "simloop/signals.hpp"

namespace simloop_py {
namespace {

using namespace pybind11::literals;

// An OutputLock that Python can release when it chooses (a with block).
struct PyOutputLock {
  std::optional<simloop::OutputLock> lock;
};

}  // namespace

void bind_outputs(py::module_& m) {
  py::list signals;
  for (const int sig : simloop::kTerminatingSignals) signals.append(sig);
  m.attr("TERMINATING_SIGNALS") = py::tuple(signals);

  py::class_<PyOutputLock>(m, "OutputLock",
                           "One run at a time in an output folder (include/simloop/output_lock.hpp): held until "
                           "release() or the end of a with block; OSError if another process holds it.")
      .def(py::init([](const std::filesystem::path& dir) {
             auto held = std::make_unique<PyOutputLock>();
             py::gil_scoped_release release;
             held->lock.emplace(dir);
             return held;
           }),
           "dir"_a)
      .def("release", [](PyOutputLock& l) { l.lock.reset(); })
      .def(
          "__enter__", [](PyOutputLock& l) -> PyOutputLock& { return l; }, py::return_value_policy::reference)
      .def("__exit__", [](PyOutputLock& l, const py::args&) { l.lock.reset(); });

  py::class_<simloop::PipedFile>(m, "PipedFile",
                                 "A file another library writes through writer_path while simloop writes and checks "
                                 "its bytes (include/simloop/piped_file.hpp); committed with the run's outputs.")
      .def(py::init<std::filesystem::path>(), "target"_a)
      .def_property_readonly("writer_path", &simloop::PipedFile::writer_path)
      .def_property_readonly("target", &simloop::PipedFile::target)
      .def_property_readonly("bytes_written", &simloop::PipedFile::bytes_written)
      .def("close_writer", &simloop::PipedFile::close_writer)
      .def(
          "wait",
          [](simloop::PipedFile& f, double timeout) {
            return wait_without_gil([&](auto slice) { return f.wait_for_end(slice); }, timeout);
          },
          "timeout"_a, "Waits up to timeout seconds for the writer to close its end; True once it did.")
      .def("finish", &simloop::PipedFile::finish,
           "After the end of the stream: OSError if a write failed, else ready to be committed.");

  m.def(
      "commit_files",
      [](const std::vector<simloop::PipedFile*>& files) {
        const std::vector<simloop::PendingFile*> list = pending_files(files);
        py::gil_scoped_release release;
        simloop::commit_together(list);
      },
      "files"_a, "Puts finished PipedFiles in place, all or none (commit_together).");
}

}  // namespace simloop_py
