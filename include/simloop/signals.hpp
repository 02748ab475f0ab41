// The signals that end a run early. One list, used by the library (which
// blocks them while it puts outputs in place) and by both commands (which
// stop on each of them as on Ctrl-C: temporary files removed, earlier
// outputs kept, exit 128 + the signal's number).
#pragma once

#include <signal.h>

#include <array>

namespace simloop {

// Every signal whose default action ends the process and that a program may
// catch: a closed terminal or dropped ssh (SIGHUP), Ctrl-C (SIGINT), the
// quit key (SIGQUIT, Ctrl-backslash), kill (SIGTERM), a closed pipe (SIGPIPE), alarm(2), the user
// signals, and a CPU-time limit's warning (SIGXCPU). Not SIGXFSZ: the
// commands ignore it, so that writing past a file-size limit is an error
// (EFBIG) they report. Python ignores SIGPIPE itself (a closed pipe is an
// EPIPE error there), so python -m simloop leaves it ignored.
inline constexpr std::array<int, 9> kTerminatingSignals = {SIGHUP,  SIGINT,  SIGQUIT, SIGTERM, SIGPIPE,
                                                           SIGALRM, SIGUSR1, SIGUSR2, SIGXCPU};

// "SIGHUP", "SIGINT", ... for the signals above, "a signal" for any other.
// Async-signal-safe (a handler may call it).
constexpr const char* signal_name(int sig) noexcept {
  switch (sig) {
    case SIGHUP:
      return "SIGHUP";
    case SIGINT:
      return "SIGINT";
    case SIGQUIT:
      return "SIGQUIT";
    case SIGTERM:
      return "SIGTERM";
    case SIGPIPE:
      return "SIGPIPE";
    case SIGALRM:
      return "SIGALRM";
    case SIGUSR1:
      return "SIGUSR1";
    case SIGUSR2:
      return "SIGUSR2";
    case SIGXCPU:
      return "SIGXCPU";
    default:
      return "a signal";
  }
}

}  // namespace simloop
