// Compiling a model in a child process, so that a compile that fails leaves
// this process as it was.
//
// MuJoCo 2.2's mj_loadXML deletes the model it parsed (mjCModel) when the
// compiler reports an error, but not when a C++ exception leaves the
// compiler: a scene that exhausts memory (<size nkey="5000000"/> under
// ulimit -v 1000000: std::bad_alloc while it makes the keyframes) leaks
// every object the parser and compiler made (924 MiB of heap in that case),
// so the next call fails too; and the compiler's thread-local error handler
// stays installed, so the next MuJoCo error on that thread longjmps into the
// compiler's finished frame and aborts the process. Neither can be undone
// from outside libmujoco. So the parse and compile run in a forked child,
// which sends back the compiled model in MuJoCo's binary format (mjb, the
// format of Model::to_bytes: the same bits), the compiler's warnings, or the
// error; whatever fails there goes with the child.
#pragma once

#include <mujoco/mujoco.h>

#include <string>
#include <string_view>
#include <vector>

namespace simloop::detail {

// Parses and compiles `filename` (from `vfs`, or the disk if null) in a
// child process. Returns the model (the caller owns it; mj_deleteModel), or
// throws MujocoError with the message load_xml would give (naming `source`).
// The load's warnings (the compiler's, and those MuJoCo's warning handler
// reported) are appended to `warnings`. Returns nullptr when no child can
// be made (fork refused: a process limit, a sandbox): the caller then loads
// in this process.
mjModel* load_xml_in_child(const char* filename, const mjVFS* vfs, std::string_view source,
                           std::vector<std::string>& warnings);

// The same in this process (what load_xml_in_child runs in its child, and
// the fallback): after a C++ exception out of MuJoCo it resets the thread's
// MuJoCo handlers, but the memory the compiler had is lost. It installs the
// handlers but loads no plugin library: a caller loading a scene from
// outside has called install_mujoco_handlers() (the chapter's scene needs none).
mjModel* load_xml_here(const char* filename, const mjVFS* vfs, std::string_view source,
                       std::vector<std::string>& warnings);

}  // namespace simloop::detail
