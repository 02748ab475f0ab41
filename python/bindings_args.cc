// Python arguments as the C++ values they become, or a one-line TypeError or
// ValueError naming the argument (pybind11's own TypeError lists every
// signature over several lines). The package's own checks (simloop._checks)
// use these too, so each argument type has one wording.
#include <pybind11/gil_safe_call_once.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>

#include "bindings_common.hpp"
#include "simloop/object_names.hpp"
#include "simloop/rows.hpp"

namespace simloop_py {

using namespace pybind11::literals;

namespace {

// The Python types the checks test against, looked up once: some checks run
// on every call of a stepping loop (Sim.ctrl = value), where importing the
// modules again each time would double their cost. Kept for the process's
// life, as pybind11 keeps its own.
struct PythonTypes {
  py::object path_like, fsdecode, real;
};
const PythonTypes& python_types() {
  PYBIND11_CONSTINIT static py::gil_safe_call_once_and_store<PythonTypes> storage;
  return storage
      .call_once_and_store_result([] {
        const py::module_ os = py::module_::import("os");
        return PythonTypes{os.attr("PathLike"), os.attr("fsdecode"), py::module_::import("numbers").attr("Real")};
      })
      .get_stored();
}

}  // namespace

std::string show(const py::handle& value) {
  py::str text;
  try {
    text = py::repr(value);
  } catch (const py::error_already_set&) {  // an int past Python's digit limit, or a broken __repr__
    if (PyLong_Check(value.ptr())) {
      return "an int of " + std::to_string(value.attr("bit_length")().cast<long long>()) + " bits";
    }
    return std::string("a ") + Py_TYPE(value.ptr())->tp_name;
  }
  py::list lines;  // one line: numpy arrays print on several
  for (const py::handle line : text.attr("splitlines")()) lines.append(line.attr("strip")());
  py::str line = py::str(" ").attr("join")(lines);
  if (py::len(line) > 80) line = py::str(line[py::slice(0, 77, 1)]).attr("__add__")("...");
  return line.cast<std::string>();
}

std::string describe(const py::handle& value) {
  return show(value) + " (" + py::type::handle_of(value).attr("__name__").cast<std::string>() + ")";
}

py::str check_path(const std::string& name, const py::handle& value, const std::string& what) {
  py::object path = py::reinterpret_borrow<py::object>(value);
  const bool str = py::isinstance<py::str>(value);  // a str is its own path: no call to make
  if (py::isinstance<py::bytes>(value) || (!str && py::isinstance(value, python_types().path_like))) {
    try {
      path = python_types().fsdecode(value);
    } catch (py::error_already_set& e) {  // an os.PathLike whose __fspath__ returns neither
      if (!e.matches(PyExc_TypeError)) throw;
    }
  }
  if (!py::isinstance<py::str>(path)) {
    throw py::type_error(name + " must be a path (str, bytes or os.PathLike), got " + describe(value));
  }
  const auto text = path.cast<py::str>();
  if (py::len(text) == 0) throw py::value_error(name + " must name " + what + ", got ''");
  if (text.contains(py::str("\0", 1))) {
    throw py::value_error(name + " must not contain a NUL character, got " + show(text));
  }
  return text;
}

py::bytes check_text(const std::string& name, const py::handle& value) {
  if (py::isinstance<py::bytes>(value)) return py::reinterpret_borrow<py::bytes>(value);
  if (!py::isinstance<py::str>(value)) throw py::type_error(name + " must be a str or bytes, got " + describe(value));
  PyObject* utf8 = PyUnicode_AsUTF8String(value.ptr());
  if (utf8 != nullptr) return py::reinterpret_steal<py::bytes>(utf8);
  py::error_already_set error;
  if (!error.matches(PyExc_UnicodeEncodeError)) throw error;
  const auto start = error.value().attr("start").cast<py::ssize_t>();
  const py::object bad = value[py::slice(start, start + 1, 1)];
  throw py::value_error(name + " must be text that UTF-8 can encode, got " + show(bad) + " at index " +
                        std::to_string(start));
}

double check_real(const std::string& name, const py::handle& value) {
  if (PyFloat_Check(value.ptr())) return PyFloat_AS_DOUBLE(value.ptr());  // the common case (numpy's float64 too)
  if (PyBool_Check(value.ptr()) || !py::isinstance(value, python_types().real)) {
    throw py::type_error(name + " must be a number, got " + describe(value));
  }
  const double number = PyFloat_AsDouble(value.ptr());
  if (number == -1.0 && PyErr_Occurred()) {
    py::error_already_set error;
    if (!error.matches(PyExc_OverflowError)) throw error;
    throw py::value_error(name + " must be a number a float can hold, got " + show(value));
  }
  return number;
}

void set_error_fs(PyObject* type, const char* what) {
  std::string line;
  bool line_break = false;
  for (const char* c = what; *c; ++c) {
    if (*c == '\n' || *c == '\r') {
      line_break = true;
      continue;
    }
    if (line_break && !line.empty() && line.back() != ' ' && *c != ' ') line += ' ';
    line_break = false;
    line += *c;
  }
  PyObject* message = PyUnicode_DecodeFSDefaultAndSize(line.data(), static_cast<py::ssize_t>(line.size()));
  if (!message) {
    PyErr_Clear();
    PyErr_SetString(type, "(undecodable message)");
    return;
  }
  PyErr_SetObject(type, message);
  Py_DECREF(message);
}

void bind_args(py::module_& m) {
  m.def("_show", &show, "value"_a, "repr(value) for an error message: one line, at most 80 characters.");
  m.def("_describe", &describe, "value"_a, "show(value) and its type's name.");
  m.def("_check_path", &check_path, "name"_a, "value"_a, "what"_a);
  m.def("_check_text", &check_text, "name"_a, "value"_a);
  m.def("_check_real", &check_real, "name"_a, "value"_a);
  m.def("_did_you_mean", &simloop::did_you_mean, "name"_a, "candidates"_a, "The likely typo's fix, or '': one rule.");
  m.attr("MAX_THREADS") = simloop::kMaxThreads;
  m.def("check_threads", &simloop::check_threads, "threads"_a, "ValueError unless threads is from 0 to MAX_THREADS.");
}

}  // namespace simloop_py
