#include "offscreen_gl.hpp"

#define EGL_NO_PROTOTYPES  // every EGL function comes from the dlopen'ed library
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>
#include <unistd.h>

#include <cstdio>
#include <mutex>
#include <string>
#include <vector>

#include "simloop/errors.hpp"

namespace simloop::detail {
namespace {

constexpr const char* kInstall =
    "rendering needs EGL and an OpenGL driver (Debian: apt install libegl1 libgl1-mesa-dri)";

std::string hex(EGLint code) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%04X", static_cast<unsigned>(code));
  return text;
}

// libEGL's functions, looked up once. RTLD_GLOBAL: MuJoCo's own GL loader
// finds eglGetProcAddress in the process's global symbols first, before it
// guesses from the libraries loaded (a libGL already loaded for GLX would
// otherwise win).
struct Egl {
  PFNEGLGETPROCADDRESSPROC GetProcAddress = nullptr;
  PFNEGLGETERRORPROC GetError = nullptr;
  PFNEGLINITIALIZEPROC Initialize = nullptr;
  PFNEGLCHOOSECONFIGPROC ChooseConfig = nullptr;
  PFNEGLBINDAPIPROC BindAPI = nullptr;
  PFNEGLCREATECONTEXTPROC CreateContext = nullptr;
  PFNEGLDESTROYCONTEXTPROC DestroyContext = nullptr;
  PFNEGLMAKECURRENTPROC MakeCurrent = nullptr;
  PFNEGLGETDISPLAYPROC GetDisplay = nullptr;
  PFNEGLQUERYDEVICESEXTPROC QueryDevicesEXT = nullptr;
  PFNEGLGETPLATFORMDISPLAYEXTPROC GetPlatformDisplayEXT = nullptr;
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLConfig config = nullptr;
  std::string failure;  // why there is no display, when there is none
  pid_t pid = 0;        // the process that made the display
};

template <class F>
bool find(void* library, const char* name, F& out) {
  out = reinterpret_cast<F>(dlsym(library, name));
  return out != nullptr;
}

// A display that has an OpenGL config with depth and stencil; false if not.
bool try_display(Egl& egl, EGLDisplay display, const std::string& what, std::vector<std::string>& tried) {
  if (display == EGL_NO_DISPLAY) {
    tried.push_back(what + ": no display");
    return false;
  }
  EGLint major = 0, minor = 0;
  if (egl.Initialize(display, &major, &minor) != EGL_TRUE) {
    tried.push_back(what + ": eglInitialize failed (" + hex(egl.GetError()) + ")");
    return false;
  }
  const EGLint attributes[] = {EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8, EGL_ALPHA_SIZE, 8, EGL_DEPTH_SIZE,
                               24, EGL_STENCIL_SIZE, 8, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                               // (the default, a window config, is what a device or the
                               // surfaceless platform lacks; MuJoCo draws into its own
                               // framebuffer, so any surface type does)
                               EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_NONE};
  EGLint found = 0;
  EGLConfig config = nullptr;
  if (egl.ChooseConfig(display, attributes, &config, 1, &found) != EGL_TRUE || found < 1) {
    tried.push_back(what + ": no OpenGL config with depth and stencil");
    return false;
  }
  egl.display = display;
  egl.config = config;
  return true;
}

Egl load_egl() {
  Egl egl;
  egl.pid = getpid();
  void* library = dlopen("libEGL.so.1", RTLD_NOW | RTLD_GLOBAL);
  if (library == nullptr) {
    egl.failure = std::string("cannot load libEGL.so.1: ") + kInstall;
    return egl;
  }
  if (!find(library, "eglGetProcAddress", egl.GetProcAddress) || !find(library, "eglGetError", egl.GetError) ||
      !find(library, "eglInitialize", egl.Initialize) || !find(library, "eglChooseConfig", egl.ChooseConfig) ||
      !find(library, "eglBindAPI", egl.BindAPI) || !find(library, "eglCreateContext", egl.CreateContext) ||
      !find(library, "eglDestroyContext", egl.DestroyContext) || !find(library, "eglMakeCurrent", egl.MakeCurrent) ||
      !find(library, "eglGetDisplay", egl.GetDisplay)) {
    egl.failure = "libEGL.so.1 lacks the EGL 1.4 functions";
    return egl;
  }
  egl.QueryDevicesEXT = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(egl.GetProcAddress("eglQueryDevicesEXT"));
  egl.GetPlatformDisplayEXT =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(egl.GetProcAddress("eglGetPlatformDisplayEXT"));

  // Devices first (a GPU, or Mesa's software device), then Mesa's
  // surfaceless platform, then whatever the default display is: none of
  // them needs a window system.
  std::vector<std::string> tried;
  if (egl.QueryDevicesEXT != nullptr && egl.GetPlatformDisplayEXT != nullptr) {
    EGLDeviceEXT devices[16];
    EGLint count = 0;
    if (egl.QueryDevicesEXT(16, devices, &count) == EGL_TRUE) {
      for (EGLint i = 0; i < count; ++i) {
        if (try_display(egl, egl.GetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr),
                        "EGL device " + std::to_string(i), tried)) {
          return egl;
        }
      }
    }
    if (try_display(egl, egl.GetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr),
                    "surfaceless platform", tried)) {
      return egl;
    }
  }
  if (try_display(egl, egl.GetDisplay(EGL_DEFAULT_DISPLAY), "default display", tried)) return egl;
  egl.failure = "no EGL display can render";
  for (const std::string& t : tried) egl.failure += "; " + t;
  egl.failure += std::string(" (") + kInstall + ")";
  return egl;
}

// One display for the process, initialised once and never terminated:
// eglTerminate would end every context on it, and each renderer has one.
Egl& egl_once() {
  static Egl egl = load_egl();
  return egl;
}

}  // namespace

struct OffscreenGl::Impl {
  Egl& egl;
  EGLContext context = EGL_NO_CONTEXT;
  std::mutex current;  // held from make_current to release
};

std::shared_ptr<OffscreenGl> OffscreenGl::shared() {
  static std::mutex mutex;
  static std::weak_ptr<OffscreenGl> context;
  const std::lock_guard<std::mutex> lock(mutex);
  std::shared_ptr<OffscreenGl> gl = context.lock();
  if (gl == nullptr || gl->impl_->egl.pid != getpid()) {
    gl = std::make_shared<OffscreenGl>();
    context = gl;
  }
  return gl;
}

namespace {

// EGL's display and Mesa's threads do not survive fork(): a child of a
// process that rendered would wait forever on them. Said instead.
void check_not_forked(const Egl& egl) {
  if (egl.pid != getpid()) {
    throw RenderError(
        "cannot render in a process forked from one that had already rendered (EGL and its driver's threads do "
        "not survive fork): start worker processes with 'spawn' or 'forkserver' (for Gymnasium's AsyncVectorEnv: "
        "context='spawn')");
  }
}

}  // namespace

OffscreenGl::OffscreenGl() : impl_(new Impl{egl_once(), EGL_NO_CONTEXT, {}}) {
  Egl& egl = impl_->egl;
  check_not_forked(egl);
  if (egl.display == EGL_NO_DISPLAY) throw RenderError(egl.failure);
  if (egl.BindAPI(EGL_OPENGL_API) != EGL_TRUE) {
    throw RenderError("EGL cannot bind desktop OpenGL (" + hex(egl.GetError()) + "): " + kInstall);
  }
  // No attributes: a compatibility-profile context, which MuJoCo's
  // fixed-function renderer needs.
  impl_->context = egl.CreateContext(egl.display, egl.config, EGL_NO_CONTEXT, nullptr);
  if (impl_->context == EGL_NO_CONTEXT) {
    throw RenderError("EGL could not create an OpenGL context (" + hex(egl.GetError()) + ")");
  }
}

OffscreenGl::~OffscreenGl() {
  // (in a forked child the context is the parent's: nothing of ours to free)
  if (impl_->context != EGL_NO_CONTEXT && impl_->egl.pid == getpid()) {
    impl_->egl.DestroyContext(impl_->egl.display, impl_->context);
  }
}

void OffscreenGl::make_current() {
  Egl& egl = impl_->egl;
  check_not_forked(egl);
  std::unique_lock<std::mutex> lock(impl_->current);
  // Without a surface (EGL_KHR_surfaceless_context): MuJoCo draws into its
  // own offscreen framebuffer.
  if (egl.MakeCurrent(egl.display, EGL_NO_SURFACE, EGL_NO_SURFACE, impl_->context) != EGL_TRUE) {
    throw RenderError("EGL could not make the OpenGL context current (" + hex(egl.GetError()) + ")");
  }
  lock.release();  // until release()
}

void OffscreenGl::release() noexcept {
  Egl& egl = impl_->egl;
  if (egl.pid != getpid()) return;  // the parent's context: never touched here
  egl.MakeCurrent(egl.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  impl_->current.unlock();
}

}  // namespace simloop::detail
