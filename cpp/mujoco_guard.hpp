// Keeps MuJoCo from doing anything behind our back.
//
// MuJoCo 2.2's default error handler appends to MUJOCO_LOG.TXT in the working
// directory, waits for Enter and exits the process; its warning handler also
// writes that file. We install process-wide handlers once: warnings go to the
// CaptureWarnings of the thread, if one is listening (loading a model), and
// are dropped otherwise inside simloop's own calls (the library reads stepping
// warnings from mjData's warning counters, which is where they belong per
// run); a warning raised outside simloop's calls (the process's own MuJoCo
// code) goes to the handler installed before ours, or, with none, to MuJoCo's
// default (MUJOCO_LOG.TXT and stdout), as it would without simloop. An error
// jumps back with longjmp to the innermost `call_catching_mujoco_error` on
// this thread, which then reports failure so the caller can throw a C++
// exception from ordinary C++ frames.
// No C++ exception ever unwinds through MuJoCo's C frames.
#pragma once

#include <exception>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "simloop/errors.hpp"

namespace simloop::detail {

// Installs the handlers and, on MuJoCo 3, loads the plugin libraries that
// ship beside libmujoco (idempotent, thread-safe). Every entry point that
// creates a model calls it, so users never have to. The chapter's own
// scene names no plugin and needs only the handlers (plugins = false):
// loading a dozen plugin libraries costs sim_loop 1 MiB of peak memory.
void install_mujoco_handlers(bool plugins = true);

// Runs fn(context). Returns false if MuJoCo raised an error inside it; the
// message is then in last_mujoco_error(). fn must not hold C++ objects with
// non-trivial destructors on its stack: a MuJoCo error skips them.
[[nodiscard]] bool call_catching_mujoco_error(void (*fn)(void*), void* context) noexcept;

// The message of the last MuJoCo error caught on this thread.
[[nodiscard]] const char* last_mujoco_error() noexcept;

// While it lives, the warnings MuJoCo reports through its warning handler on
// this thread are kept (the XML parser's "XML contains a 'NaN'", for one).
class CaptureWarnings {
 public:
  CaptureWarnings() noexcept;
  ~CaptureWarnings();
  CaptureWarnings(const CaptureWarnings&) = delete;
  CaptureWarnings& operator=(const CaptureWarnings&) = delete;
  [[nodiscard]] std::vector<std::string> take() { return std::move(warnings_); }

 private:
  std::vector<std::string> warnings_;
  std::vector<std::string>* previous_;
};

// MuJoCo 2.2's compiler installs thread-local error and warning handlers of
// its own and puts the previous ones back only when it returns or fails with
// a compile error: a C++ exception out of it (std::bad_alloc) leaves its
// error handler in place, and the next MuJoCo error on the thread would
// longjmp into the compiler's finished frame (the process aborts). Clears
// them, for after such an exception.
void reset_mujoco_thread_handlers() noexcept;

using simloop::one_line;  // include/simloop/errors.hpp

// The MujocoError for a C++ exception that came out of MuJoCo (its XML
// parser and compiler are C++ inside libmujoco: std::bad_alloc, for one).
[[nodiscard]] MujocoError error_from_exception(const std::exception_ptr& error);

// Calls `f()` (a lambda that only calls MuJoCo functions) and throws
// MujocoError with MuJoCo's message, on one line, if MuJoCo raised an error.
// A C++ exception thrown inside MuJoCo is caught before it reaches the
// guard's C frames (it would end the process there) and rethrown from here as
// a MujocoError ("out of memory" for std::bad_alloc).
template <class F>
void mujoco_call(F&& f) {
  using Fn = std::remove_reference_t<F>;
  struct Context {
    Fn* fn;
    std::exception_ptr error;
  } context{&f, nullptr};
  auto trampoline = [](void* p) noexcept {
    auto* c = static_cast<Context*>(p);
    try {
      (*c->fn)();
    } catch (...) {
      c->error = std::current_exception();
    }
  };
  if (!call_catching_mujoco_error(trampoline, &context)) {
    throw MujocoError(one_line(last_mujoco_error()));
  }
  if (context.error) throw error_from_exception(context.error);
}

}  // namespace simloop::detail
