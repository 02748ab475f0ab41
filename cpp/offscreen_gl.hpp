// An OpenGL context without a window or a display server, for MuJoCo's
// renderer: EGL on a device (a GPU, or Mesa's software rasteriser) or on
// Mesa's surfaceless platform. libEGL is opened when the first context is
// made, not linked: a process that never renders never loads it, and a
// machine without it can do everything else (RenderError says what to
// install when a picture is asked for).
#pragma once

#include <memory>

namespace simloop::detail {

class OffscreenGl {
 public:
  // The process's one context, made when the first renderer asks and gone
  // with the last: every renderer draws in it with objects of its own (a
  // context costs ~70 MiB of address space on Mesa, and the 50th of them
  // failed under a 1 GB ulimit -v). Throws RenderError as the constructor.
  [[nodiscard]] static std::shared_ptr<OffscreenGl> shared();

  // Throws RenderError naming what is missing (libEGL, a display, a config).
  OffscreenGl();
  ~OffscreenGl();
  OffscreenGl(const OffscreenGl&) = delete;
  OffscreenGl& operator=(const OffscreenGl&) = delete;

  // Makes the context current on this thread (MuJoCo's mjr_ calls draw into
  // the current one), and releases it again, so another thread may take it;
  // in between, no other thread can make it current (make_current waits).
  void make_current();
  void release() noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace simloop::detail
