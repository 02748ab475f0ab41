// Where MuJoCo's warnings go: the seam between MuJoCo 2.2 and 3.x's legacy
// warning handler (mju_user_warning) and MuJoCo 4's log handler
// (mju_setLogHandler), for mujoco_guard.cc. A warning raised inside one of
// simloop's calls goes to simloop; any other goes exactly where MuJoCo would
// have sent it had simloop installed nothing.
#include <mujoco/mujoco.h>

#include <cstdio>
#include <mutex>

#include "mujoco_compat.hpp"

namespace simloop::detail::compat {
namespace {

WarningRoute g_route{};  // set once, before any handler of ours is installed

#if mjVERSION_HEADER >= 4000000
// MuJoCo 4 sends every message to one log handler; its default one prints a
// warning to stderr and appends it to MUJOCO_LOG.TXT unless a legacy
// mju_user_warning is set. Ours takes warnings raised inside simloop's calls
// and passes everything else to the handler that was active before it.
mjfLogHandler g_previous = nullptr;

void on_log(const mjLogMessage* message) {
  if (message->level == mjLOG_WARNING && g_route.in_simloop()) {
    char text[2048];
    if (message->func != nullptr) {  // as MuJoCo words it for a legacy handler
      std::snprintf(text, sizeof text, "%s: %s", message->func, message->subject);
    } else {
      std::snprintf(text, sizeof text, "%s", message->subject);
    }
    g_route.simloop(text);
    return;
  }
  g_previous(message);
}
#else
// MuJoCo 2.2 and 3.x call mju_user_warning, or with none write the warning
// to MUJOCO_LOG.TXT and print it.
void (*g_previous)(const char*) = nullptr;

extern "C" void on_warning(const char* message) {
  if (g_route.in_simloop()) {
    g_route.simloop(message);
  } else if (g_previous != nullptr) {
    g_previous(message);
  } else {  // MuJoCo's own default, word for word
    const char* const text = message ? message : "";
    mju_writeLog("WARNING", text);
    std::printf("WARNING: %s\n\n", text);
  }
}
#endif

}  // namespace

void install_warning_route(WarningRoute route) {
  static std::once_flag once;
  std::call_once(once, [&] {
    g_route = route;
#if mjVERSION_HEADER >= 4000000
    g_previous = mju_setLogHandler(on_log);  // never null: MuJoCo's default at least
#else
    g_previous = mju_user_warning;
    mju_user_warning = on_warning;
#endif
  });
}

}  // namespace simloop::detail::compat
