// simloop._core: glue between the C++ library and Python, one file a topic
// (bindings_<topic>.cc). No simulation logic lives here: arguments are
// converted, the GIL is released around the C++ work, and results are handed
// back as numpy views or plain Python values. Values are checked once, by
// the library; the Python package only turns wrong types into clear errors.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "bindings_common.hpp"
#include "simloop/errors.hpp"
#include "simloop/version.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_core, m) {
  using simloop_py::OutOfMemory;
  using simloop_py::ResourceFailure;
  using simloop_py::set_error_fs;
  m.doc() = "simloop's compiled core: the chapter's MuJoCo loop in C++ (use the simloop package).";
  m.attr("__version__") = simloop::kVersion;
  m.attr("MUJOCO_VERSION") = simloop::mujoco_version();

  static py::exception<simloop::MujocoError> mujoco_error(m, "MujocoError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const simloop::MujocoError& e) {
      set_error_fs(mujoco_error.ptr(), e.what());
    } catch (const simloop::InvalidArgument& e) {
      set_error_fs(PyExc_ValueError, e.what());
    } catch (const simloop::IoError& e) {
      set_error_fs(PyExc_OSError, e.what());
    } catch (const simloop::Error& e) {
      set_error_fs(PyExc_RuntimeError, e.what());
    } catch (const OutOfMemory& e) {
      set_error_fs(PyExc_MemoryError, e.what());
    } catch (const ResourceFailure& e) {
      set_error_fs(PyExc_RuntimeError, e.what());
    }
  });

  simloop_py::bind_args(m);
  simloop_py::bind_model(m);
  simloop_py::bind_record(m);
  simloop_py::bind_chapter(m);
  simloop_py::bind_scenario(m);
  simloop_py::bind_sim(m);
  simloop_py::bind_render(m);
  simloop_py::bind_command(m);
  simloop_py::bind_outputs(m);
}
