# MuJoCo from the PyPI `mujoco` package (SIMLOOP_MUJOCO=pypi): the libmujoco
# and headers it ships in site-packages/mujoco/ (3.x in `mujoco` itself, 4.x
# in its dependency `mujoco-core`, same folder), found through a Python that
# has the package installed: SIMLOOP_MUJOCO_PYTHON, else Python_EXECUTABLE,
# else python3 on PATH. Defines the imported target mujoco::mujoco, as
# Debian's mujocoConfig.cmake does, and:
#
#   SIMLOOP_MUJOCO_LIBRARY_VERSION  the library's version, from its file name (3.17.0)
#   SIMLOOP_MUJOCO_PACKAGE_DIR      the folder holding libmujoco.so.<version>
#
# Programs built here get that folder as their run-time search path; the
# Python module gets $ORIGIN/../mujoco instead (set where it is built), so
# it loads the very file `import mujoco` loads, from the environment it is
# installed in. The library's SONAME carries the full version, so a module
# built against 3.17.0 loads only 3.17.0: simloop/__init__.py turns the
# loader's error into one line naming both versions.

set(SIMLOOP_MUJOCO_MIN_VERSION 3.3)   # the oldest with mj_getState/mj_setState's integration state and plugins as used here
set(SIMLOOP_MUJOCO_BELOW_VERSION 5)   # the supported range ends before 5.0

if(SIMLOOP_MUJOCO_PYTHON)
  set(_simloop_python "${SIMLOOP_MUJOCO_PYTHON}")
elseif(Python_EXECUTABLE)
  set(_simloop_python "${Python_EXECUTABLE}")
else()
  find_program(_simloop_python NAMES python3 python)
endif()

# Where the package is, without importing it (the import loads numpy and
# the renderer; we only need the folder).
execute_process(
  COMMAND "${_simloop_python}" -c
    "import importlib.util as u; s = u.find_spec('mujoco'); print(s.submodule_search_locations[0] if s and s.submodule_search_locations else '')"
  OUTPUT_VARIABLE _simloop_mujoco_dir
  OUTPUT_STRIP_TRAILING_WHITESPACE
  RESULT_VARIABLE _simloop_status)
if(NOT _simloop_status EQUAL 0 OR NOT _simloop_mujoco_dir)
  message(FATAL_ERROR
    "SIMLOOP_MUJOCO=pypi: the Python at ${_simloop_python} has no `mujoco` package. "
    "Install it there (pip install mujoco, ${SIMLOOP_MUJOCO_MIN_VERSION} to below ${SIMLOOP_MUJOCO_BELOW_VERSION}.0), "
    "or name another Python with -DSIMLOOP_MUJOCO_PYTHON=...")
endif()

file(GLOB _simloop_libs LIST_DIRECTORIES false "${_simloop_mujoco_dir}/libmujoco.so.*")
list(LENGTH _simloop_libs _simloop_nlibs)
if(NOT _simloop_nlibs EQUAL 1 OR NOT EXISTS "${_simloop_mujoco_dir}/include/mujoco/mujoco.h")
  message(FATAL_ERROR
    "SIMLOOP_MUJOCO=pypi: ${_simloop_mujoco_dir} should hold one libmujoco.so.<version> and include/mujoco/mujoco.h "
    "(found ${_simloop_nlibs} libraries); is the mujoco package complete?")
endif()
get_filename_component(_simloop_lib_name "${_simloop_libs}" NAME)
string(REGEX REPLACE "^libmujoco\\.so\\." "" SIMLOOP_MUJOCO_LIBRARY_VERSION "${_simloop_lib_name}")
if(SIMLOOP_MUJOCO_LIBRARY_VERSION VERSION_LESS SIMLOOP_MUJOCO_MIN_VERSION OR
   NOT SIMLOOP_MUJOCO_LIBRARY_VERSION VERSION_LESS SIMLOOP_MUJOCO_BELOW_VERSION)
  message(FATAL_ERROR
    "SIMLOOP_MUJOCO=pypi: found MuJoCo ${SIMLOOP_MUJOCO_LIBRARY_VERSION} in ${_simloop_mujoco_dir}; "
    "simloop supports ${SIMLOOP_MUJOCO_MIN_VERSION} to below ${SIMLOOP_MUJOCO_BELOW_VERSION}.0")
endif()
set(SIMLOOP_MUJOCO_PACKAGE_DIR "${_simloop_mujoco_dir}")

if(NOT TARGET mujoco::mujoco)
  add_library(mujoco::mujoco SHARED IMPORTED)
  set_target_properties(mujoco::mujoco PROPERTIES
    IMPORTED_LOCATION "${_simloop_libs}"
    IMPORTED_SONAME "${_simloop_lib_name}"
    INTERFACE_INCLUDE_DIRECTORIES "${_simloop_mujoco_dir}/include")
endif()
message(STATUS "simloop: MuJoCo ${SIMLOOP_MUJOCO_LIBRARY_VERSION} from the PyPI package in ${_simloop_mujoco_dir}")
unset(_simloop_libs)
unset(_simloop_nlibs)
unset(_simloop_lib_name)
unset(_simloop_mujoco_dir)
unset(_simloop_status)
