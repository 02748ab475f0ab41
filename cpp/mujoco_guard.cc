#include "mujoco_guard.hpp"

#include <mujoco/mujoco.h>

#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <new>

#include "mujoco_compat.hpp"

namespace simloop::detail {
namespace {

// Per thread: where to jump on a MuJoCo error, and the message it carried;
// where warnings go (a CaptureWarnings), if anywhere.
thread_local std::jmp_buf* t_error_target = nullptr;
thread_local char t_error_message[1024] = "";
thread_local std::vector<std::string>* t_warnings = nullptr;

// The error handler the process had before ours (the user's own, or none:
// MuJoCo's default), kept once, as ours is installed.
void (*g_previous_error)(const char*) = nullptr;

extern "C" void on_mujoco_error(const char* message) {
  std::snprintf(t_error_message, sizeof t_error_message, "%s", message ? message : "");
  if (t_error_target != nullptr) {
    std::longjmp(*t_error_target, 1);
  }
  // Outside simloop's calls, a handler of the process's own takes it, as it
  // would without simloop.
  if (g_previous_error != nullptr) {
    g_previous_error(message);
    return;
  }
  // Otherwise a MuJoCo call outside call_catching_mujoco_error is a simloop
  // bug, or the process's own call with no handler of its own. MuJoCo
  // cannot continue after an error, so stop loudly instead of returning into
  // it -- but never write MUJOCO_LOG.TXT or wait for Enter.
  std::fprintf(stderr, "simloop: MuJoCo error outside a guarded call: %s\n", t_error_message);
  std::abort();
}

// Whether a warning MuJoCo raises now is simloop's: inside one of its calls,
// or while a load listens on this thread.
bool in_simloop() noexcept { return t_warnings != nullptr || t_error_target != nullptr; }

void on_mujoco_warning(const char* message) {
  // Stepping warnings are read back from mjData::warning (counts, first step,
  // info) by the run loop; nothing is printed or logged here. A load keeps
  // what comes while it listens. (Warnings outside simloop's calls never come
  // here: compat::install_warning_route sends them where they would have
  // gone without simloop.)
  if (t_warnings == nullptr) return;
  try {
    t_warnings->emplace_back(message ? message : "");
  } catch (...) {  // out of memory: the warning is lost, nothing else
  }
}

}  // namespace

// MuJoCo's thread-local handler hooks (exported by libmujoco 2.2, not in its
// public headers); weak, so a MuJoCo without them links and skips the reset.
extern "C" {
__attribute__((weak)) void _mjPRIVATE__set_tls_error_fn(void (*h)(const char*));
__attribute__((weak)) void _mjPRIVATE__set_tls_warning_fn(void (*h)(const char*));
}

CaptureWarnings::CaptureWarnings() noexcept : previous_(t_warnings) { t_warnings = &warnings_; }

CaptureWarnings::~CaptureWarnings() { t_warnings = previous_; }

void reset_mujoco_thread_handlers() noexcept {
  if (_mjPRIVATE__set_tls_error_fn != nullptr) _mjPRIVATE__set_tls_error_fn(nullptr);
  if (_mjPRIVATE__set_tls_warning_fn != nullptr) _mjPRIVATE__set_tls_warning_fn(nullptr);
}

namespace {
void set_handlers_once() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (mju_user_error != on_mujoco_error) g_previous_error = mju_user_error;
    mju_user_error = on_mujoco_error;
    compat::install_warning_route({in_simloop, on_mujoco_warning});
  });
}
}  // namespace

void install_mujoco_handlers(bool plugins) {
  set_handlers_once();
  // Plugins load under the handlers (and call_catching_mujoco_error): a
  // failing plugin library must not reach MuJoCo's default error handler.
  if (plugins) compat::load_plugins_once();
}

bool call_catching_mujoco_error(void (*fn)(void*), void* context) noexcept {
  set_handlers_once();
  std::jmp_buf target;
  std::jmp_buf* const enclosing = t_error_target;
  if (setjmp(target) != 0) {
    t_error_target = enclosing;
    return false;
  }
  t_error_target = &target;
  fn(context);
  t_error_target = enclosing;
  return true;
}

const char* last_mujoco_error() noexcept { return t_error_message; }

MujocoError error_from_exception(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const std::bad_alloc&) {
    return MujocoError("MuJoCo ran out of memory");
  } catch (const std::exception& e) {
    return MujocoError("MuJoCo failed: " + one_line(e.what()));
  } catch (...) {
    return MujocoError("MuJoCo failed with an unknown C++ exception");
  }
}

}  // namespace simloop::detail

namespace simloop {

namespace {

// A control character as \xNN: it would otherwise act on the terminal.
void append_escaped(std::string& out, char c) {
  static constexpr char kHex[] = "0123456789abcdef";
  const auto byte = static_cast<unsigned char>(c);
  out += "\\x";
  out += kHex[byte >> 4];
  out += kHex[byte & 0xf];
}

bool is_control(char c) {
  const auto byte = static_cast<unsigned char>(c);
  return byte < 0x20 || byte == 0x7f;
}

}  // namespace

std::string one_line(std::string_view text) {
  std::string line;
  bool pending_separator = false;
  for (const char c : text) {
    if (c == '\n' || c == '\r') {
      pending_separator = !line.empty();
      continue;
    }
    if (pending_separator) {
      line += "; ";
      pending_separator = false;
    }
    if (is_control(c) && c != '\t') {
      append_escaped(line, c);
    } else {
      line += c;
    }
  }
  while (!line.empty() && (line.back() == ' ' || line.back() == '\t')) line.pop_back();
  return line;
}

std::string printable(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    if (is_control(c) && c != '\n' && c != '\t') {
      append_escaped(out, c);
    } else {
      out += c;
    }
  }
  return out;
}

std::string quoted_value(std::string_view value, std::size_t max_bytes) {
  std::string out = "'";
  for (const char c : value.substr(0, max_bytes)) {
    if (c == '\'' || c == '\\') {
      out += '\\';
      out += c;
    } else if (is_control(c)) {
      append_escaped(out, c);
    } else {
      out += c;
    }
  }
  out += "'";
  if (value.size() > max_bytes)
    out += " (" + std::to_string(max_bytes) + " of its " + std::to_string(value.size()) + " bytes)";
  return out;
}

}  // namespace simloop
