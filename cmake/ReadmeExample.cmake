# Writes the README's C++ example (its one ```cpp block) to OUT, so that the
# tests build and run the very program a reader copies. Run at build time:
# cmake -DIN=README.md -DOUT=... -P this.
include(${CMAKE_CURRENT_LIST_DIR}/TakeBlock.cmake)
simloop_take_block("${IN}" "```cpp\n" "```" _code)
simloop_write_if_changed("${OUT}" "// Generated from ${IN} by cmake/ReadmeExample.cmake: do not edit.\n${_code}")
