// The library's errors. It never prints and never exits: every failure is
// one of these, thrown to the caller (the command turns them into a message
// and an exit code, the Python module into an exception).
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace simloop {

// `text` on one line: each run of line breaks becomes "; " (MuJoCo's XML
// errors span lines), other control characters \xNN, and trailing blanks
// are dropped. Every message simloop throws is one line; the commands print
// theirs through this too.
[[nodiscard]] std::string one_line(std::string_view text);

// `text` for a terminal: control characters other than line breaks and tabs
// written \xNN (a scene's names and paths reach the report; an escape
// sequence in one would act on the terminal).
[[nodiscard]] std::string printable(std::string_view text);

// A value a user gave, for an error message: in single quotes, a quote or
// backslash escaped with a backslash, control characters written \xNN, and
// past `max_bytes` cut, saying how long it was. Every echoed value goes
// through this, so an error stays one line and nothing acts on the terminal.
[[nodiscard]] std::string quoted_value(std::string_view value, std::size_t max_bytes = 200);

// A duration in seconds (a timestep, a sweep's duration) that a run can use:
// throws InvalidArgument "<name> must be a positive, finite number of
// seconds, got <value>" otherwise. Every such check in the library is this one.
void check_positive_seconds(std::string_view name, double value);

// A count from 1 to `most` (steps, record_every, a Sim's n): throws
// InvalidArgument "<name> must be at least 1, got <value>" or "<name> must be
// at most <most>, got <value>" otherwise.
void check_count(std::string_view name, std::int64_t value, std::int64_t most);

// Base of everything simloop throws.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An argument or input that cannot be used: a bad timestep, step count,
// model file that lacks what the loop needs. The message names the input.
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

// MuJoCo itself reported an error (XML parse or compile error, or an error
// raised while stepping). The message is MuJoCo's own text.
class MujocoError : public Error {
 public:
  using Error::Error;
};

// Reading or writing a file failed; the message names the path.
class IoError : public Error {
 public:
  using Error::Error;
};

// A picture cannot be made on this machine: no EGL, no display it can
// render on, no OpenGL context. The message says what to install.
class RenderError : public Error {
 public:
  using Error::Error;
};

// The work was stopped on request (RunControl::request_stop: Ctrl-C in the
// commands, KeyboardInterrupt in Python) before it finished.
class Interrupted : public Error {
 public:
  using Error::Error;
};

}  // namespace simloop
