// Keeps MuJoCo from doing anything behind our back.
//
// MuJoCo 2.2's default error handler appends to MUJOCO_LOG.TXT in the working
// directory, waits for Enter and exits the process; its warning handler also
// writes that file. We install process-wide handlers once: warnings are
// dropped here (the library reads them from mjData's warning counters, which
// is where they belong per run), and an error jumps back with longjmp to the
// innermost `call_catching_mujoco_error` on this thread, which then reports
// failure so the caller can throw a C++ exception from ordinary C++ frames.
// No C++ exception ever unwinds through MuJoCo's C frames.
#pragma once

#include <type_traits>

#include "simloop/errors.hpp"

namespace simloop::detail {

// Installs the handlers (idempotent, thread-safe). Every entry point that
// creates a model calls it, so users never have to.
void install_mujoco_handlers();

// Runs fn(context). Returns false if MuJoCo raised an error inside it; the
// message is then in last_mujoco_error(). fn must not hold C++ objects with
// non-trivial destructors on its stack: a MuJoCo error skips them.
[[nodiscard]] bool call_catching_mujoco_error(void (*fn)(void*), void* context) noexcept;

// The message of the last MuJoCo error caught on this thread.
[[nodiscard]] const char* last_mujoco_error() noexcept;

// Calls `f()` (a lambda that only calls MuJoCo C functions) and throws
// MujocoError with MuJoCo's message if MuJoCo raised an error.
template <class F>
void mujoco_call(F&& f) {
  using Fn = std::remove_reference_t<F>;
  auto trampoline = [](void* p) { (*static_cast<Fn*>(p))(); };
  if (!call_catching_mujoco_error(trampoline, &f)) {
    throw MujocoError(last_mujoco_error());
  }
}

}  // namespace simloop::detail
