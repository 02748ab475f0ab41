# Checks, before anything is built, everything simloop needs from the system,
# and stops with one message that names what is missing and the apt-get line
# that installs it (Debian 12). Without this, each gap gives a different CMake
# error, one at a time: project()'s "No CMAKE_CXX_COMPILER could be found",
# "Could not find a package configuration file provided by mujoco",
# mujocoConfig.cmake's find_dependency(OpenGL) failing (libmujoco-dev does not
# depend on the OpenGL development packages it asks for), or a missing
# /usr/include/libqhull_r that its imported target names.
#
# Included right after project(... LANGUAGES NONE): it enables CXX itself once
# it knows a compiler exists. Sets nothing else; find_package(mujoco) and the
# rest are then called as usual.
include(CheckLanguage)

set(_simloop_missing "")   # what is missing, for the message
set(_simloop_packages "")  # the Debian packages that provide it
macro(_simloop_lacks what)
  list(APPEND _simloop_missing "${what}")
  list(APPEND _simloop_packages ${ARGN})
endmacro()

# A NOTFOUND left in the cache by an earlier failed configure would make
# check_language skip the search: look again, the compiler may be installed now.
if(DEFINED CMAKE_CXX_COMPILER AND NOT CMAKE_CXX_COMPILER)
  unset(CMAKE_CXX_COMPILER CACHE)
endif()
check_language(CXX)
if(CMAKE_CXX_COMPILER)
  enable_language(CXX)
else()
  _simloop_lacks("a C++17 compiler (g++)" g++)
  # The find_* calls below search /usr/lib/<multiarch>, which CMake learns from
  # the compiler; guess it so the other checks still run and the message is complete.
  if(NOT CMAKE_LIBRARY_ARCHITECTURE AND CMAKE_HOST_SYSTEM_NAME STREQUAL "Linux")
    set(CMAKE_LIBRARY_ARCHITECTURE "${CMAKE_HOST_SYSTEM_PROCESSOR}-linux-gnu")
  endif()
endif()

# Debian's MuJoCo (SIMLOOP_MUJOCO=system). The PyPI package's headers need
# neither OpenGL nor qhull; cmake/MujocoFromPypi.cmake checks that build.
if(SIMLOOP_MUJOCO STREQUAL "system")
  # OpenGL first: mujocoConfig.cmake's find_dependency(OpenGL) then reuses it.
  find_package(OpenGL QUIET)
  if(NOT OPENGL_FOUND)
    _simloop_lacks("the OpenGL development files that MuJoCo's CMake config asks for (libgl-dev, libopengl-dev)"
                   libgl-dev libopengl-dev)
  endif()

  # mujoco_DIR is set when the config file exists, even when its OpenGL
  # dependency made it report not found.
  find_package(mujoco 2.2 CONFIG QUIET)
  if(NOT mujoco_DIR)
    _simloop_lacks("MuJoCo 2.2's development files (libmujoco-dev)" libmujoco-dev)
  endif()
endif()

# Scenario files are TOML, read with toml++.
find_package(tomlplusplus 3 CONFIG QUIET)
if(NOT tomlplusplus_FOUND)
  _simloop_lacks("toml++, which reads scenario files (libtomlplusplus-dev)" libtomlplusplus-dev)
endif()

# Debian's mujoco::mujoco names /usr/include/libqhull_r/, which only
# libqhull-dev installs. GoogleTest by its header too: find_package(GTest)
# needs a compiler already.
find_path(SIMLOOP_QHULL_INCLUDE_DIR libqhull_r/libqhull_r.h)
find_path(SIMLOOP_GTEST_INCLUDE_DIR gtest/gtest.h)
mark_as_advanced(SIMLOOP_QHULL_INCLUDE_DIR SIMLOOP_GTEST_INCLUDE_DIR)
# Pictures: the EGL headers (libEGL itself is opened at run time, by the first
# render; cpp/offscreen_gl.cc).
find_path(SIMLOOP_EGL_INCLUDE_DIR EGL/eglext.h)
mark_as_advanced(SIMLOOP_EGL_INCLUDE_DIR)
if(NOT SIMLOOP_EGL_INCLUDE_DIR)
  _simloop_lacks("the EGL headers, for offscreen rendering (libegl-dev)" libegl-dev)
endif()
if(NOT SIMLOOP_QHULL_INCLUDE_DIR AND SIMLOOP_MUJOCO STREQUAL "system")
  _simloop_lacks("the qhull headers that MuJoCo's headers include (libqhull-dev)" libqhull-dev)
endif()
if(NOT SIMLOOP_GTEST_INCLUDE_DIR AND SIMLOOP_BUILD_TESTS AND (BUILD_TESTING OR NOT DEFINED BUILD_TESTING))
  _simloop_lacks("GoogleTest, for the C++ tests (libgtest-dev, or configure with -DSIMLOOP_BUILD_TESTS=OFF)"
                 libgtest-dev)
endif()

if(SIMLOOP_BUILD_PYTHON)
  find_package(Python 3.9 QUIET COMPONENTS Interpreter Development.Module)
  if(NOT Python_Development.Module_FOUND)
    _simloop_lacks("Python's development headers, Python.h (python3-dev)" python3-dev)
  endif()
endif()

if(_simloop_missing)
  list(JOIN _simloop_missing ";\n  " _simloop_what)
  list(JOIN _simloop_packages " " _simloop_apt)
  message(FATAL_ERROR
    "simloop cannot be built; this system lacks:\n  ${_simloop_what}.\n"
    "On Debian 12, install what is missing with (as root, or through sudo):\n"
    "  apt-get install --no-install-recommends ${_simloop_apt}\n")
endif()
unset(_simloop_missing)
unset(_simloop_packages)
