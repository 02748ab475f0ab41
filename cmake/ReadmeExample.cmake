# Writes the README's C++ example (its one ```cpp block) to OUT, so that the
# tests build and run the very program a reader copies. Run at build time:
# cmake -DIN=README.md -DOUT=... -P this.
file(READ "${IN}" _text)
set(_open "```cpp\n")
string(FIND "${_text}" "${_open}" _begin)
if(_begin LESS 0)
  message(FATAL_ERROR "${IN}: no ```cpp block to build")
endif()
string(LENGTH "${_open}" _open_length)
math(EXPR _begin "${_begin} + ${_open_length}")
string(SUBSTRING "${_text}" ${_begin} -1 _text)
string(FIND "${_text}" "```" _end)
string(SUBSTRING "${_text}" 0 ${_end} _code)
file(WRITE "${OUT}.tmp" "// Generated from ${IN} by cmake/ReadmeExample.cmake: do not edit.\n${_code}")
configure_file("${OUT}.tmp" "${OUT}" COPYONLY)
file(REMOVE "${OUT}.tmp")
