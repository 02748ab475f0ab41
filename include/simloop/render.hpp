// Pictures of a simulation's state, made without a window: MuJoCo's own
// renderer (mjv_updateScene, then mjr_render into its offscreen framebuffer)
// on an OpenGL context that EGL makes on a GPU, or on Mesa's software
// rasteriser on a machine without one. What a Gymnasium env's render() and a
// run's video draw.
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "simloop/model.hpp"

namespace simloop {

// Where a picture is taken from. With neither `camera` nor `track`, a free
// camera looks at the whole scene (MuJoCo's default free camera: the
// scene's centre, from 1.5 times its extent, at the azimuth and elevation of
// its <visual><global>).
struct CameraView {
  std::string camera;  // one of the scene's cameras, by name, as the scene defines it
  std::string track;   // or a free camera that looks at this body, by name
  // or at this point (world, m): a video follows a body along the floor this
  // way, so that its hops show as the body rising in the picture
  std::optional<std::array<double, 3>> lookat;
  // A free camera's distance (m) and direction (degrees); unset: the
  // default free camera's.
  std::optional<double> distance;
  std::optional<double> azimuth;
  std::optional<double> elevation;
};

// How a renderer draws, beyond where from.
struct RenderStyle {
  // MuJoCo's multisampling (the scene's <quality offsamples>, 4 unless it
  // says): smoother edges, at about 3 times a picture's time on Mesa's
  // software rasteriser. A video's frames go without.
  bool multisample = true;
  // Planes drawn to the horizon, as the physics has them (a plane collides
  // everywhere), rather than to their size: a body that travels off the
  // drawn floor (the chapter's box, 4.9 m out by the end of a run; Break
  // It's hop, at 9 m) still has it under it: out to the far clipping plane,
  // moved under the camera for each picture. A video's frames have them.
  bool endless_planes = false;
  // The shadow map's side, in texels: 0, about 2 a pixel of the picture's
  // larger side (at least 512); else this many (kMinShadowSize to
  // kMaxShadowSize), never more than the scene's <quality shadowsize>. A
  // video's frames take 512: its shadow pass was half a frame's time, for
  // shadows no sharper to the eye in motion.
  int shadow_size = 0;
  static constexpr int kMinShadowSize = 64;
  static constexpr int kMaxShadowSize = 16384;
};

// Checks `view` against `model`, as a picture would: InvalidArgument for a
// camera or body the scene lacks (naming what it has), a free camera's
// setting beside a scene's camera, a distance that is not positive or an
// angle that is not finite. Needs no OpenGL.
void check_camera_view(const Model& model, const CameraView& view);

class Renderer {
 public:
  static constexpr int kMaxSize = 8192;  // pixels, either side

  // Draws states of `model` (or of a copy of it with other parameters: the
  // same structure) `width` x `height` pixels. Throws InvalidArgument unless
  // both are from 1 to kMaxSize and style.shadow_size is 0 or in its range, RenderError when this machine cannot render
  // (no libEGL, no display, an OpenGL MuJoCo cannot use; the message says
  // what to install; or in a process forked from one that had already
  // rendered, which EGL does not survive).
  Renderer(const Model& model, int width, int height, const RenderStyle& style = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  [[nodiscard]] int width() const noexcept;
  [[nodiscard]] int height() const noexcept;

  // Draws `d`, a state of `model` (positions and what MuJoCo derives from
  // them current, as mj_forward or mj_step leave them), seen from `view`:
  // `rgb` gets width x height x 3 bytes and `depth` width x height floats
  // (metres from the camera's plane), each row by row from the top; either
  // may be null. Reads `d`, changes nothing in it. Throws InvalidArgument
  // where check_camera_view does, and for a model of another structure than
  // the renderer's.
  // Safe from any thread; calls take turns.
  void render(const Model& model, const mjData* d, const CameraView& view, std::uint8_t* rgb, float* depth);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace simloop
