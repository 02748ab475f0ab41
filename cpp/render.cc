#include "simloop/render.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>
#include <vector>

#include "mujoco_guard.hpp"
#include "offscreen_gl.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"

namespace simloop {
namespace {

// The scene's geoms and MuJoCo's decorations (contact points, frames) drawn
// at once: MuJoCo's own Renderer allows as many.
constexpr int kMaxGeoms = 10000;

constexpr int kEndlessPlaneGrid = 100;  // quads a side (50 showed the spotlight in steps)

void check_size(const char* what, int pixels) {
  if (pixels < 1 || pixels > Renderer::kMaxSize) {
    throw InvalidArgument(std::string("the picture's ") + what + " must be from 1 to " +
                          std::to_string(Renderer::kMaxSize) + " pixels, got " + std::to_string(pixels));
  }
}

bool same_structure(const mjModel* a, const mjModel* b) {
  return a->nq == b->nq && a->nv == b->nv && a->nbody == b->nbody && a->ngeom == b->ngeom && a->ncam == b->ncam &&
         a->nlight == b->nlight && a->nsite == b->nsite && a->nmesh == b->nmesh;
}

// The view as MuJoCo's camera, its names looked up and its settings checked;
// with `d`, a tracked body's centre from that state.
mjvCamera camera_for(const mjModel* m, const mjData* d, const CameraView& view) {
  mjvCamera camera;
  mjv_defaultCamera(&camera);
  const bool free_settings = view.distance || view.azimuth || view.elevation;
  if (!view.camera.empty()) {
    if (!view.track.empty() || view.lookat) {
      throw InvalidArgument(
          "a picture is taken from a scene's camera ('" + view.camera + "') or a free camera looking at " +
          (view.track.empty() ? std::string("a point") : "a body ('" + view.track + "')") + ", not both");
    }
    if (free_settings) {
      throw InvalidArgument("camera '" + view.camera +
                            "' is the scene's own: distance, azimuth and elevation are for a free camera");
    }
    camera.type = mjCAMERA_FIXED;
    camera.fixedcamid = object_id(m, mjOBJ_CAMERA, view.camera);
    return camera;
  }
  mjv_defaultFreeCamera(m, &camera);
  if (view.lookat) {
    if (!view.track.empty()) {
      throw InvalidArgument("a free camera looks at a body ('" + view.track + "') or at a point, not both");
    }
    for (double x : *view.lookat) {
      if (!std::isfinite(x)) {
        throw InvalidArgument("the camera's lookat must be 3 finite numbers of metres, got " + python_float_repr(x));
      }
    }
    std::copy(view.lookat->begin(), view.lookat->end(), camera.lookat);
  }
  if (!view.track.empty()) {
    // A free camera looking at the body's subtree centre of mass. (MuJoCo's
    // mjCAMERA_TRACKING moves its lookat a fifth of the way there per
    // picture, smoothing a viewer's motion; a picture here stands alone.)
    const int body = object_id(m, mjOBJ_BODY, view.track);
    if (d != nullptr) std::copy_n(d->subtree_com + 3 * body, 3, camera.lookat);
  }
  if (view.distance) {
    if (!(*view.distance > 0.0) || !std::isfinite(*view.distance)) {
      throw InvalidArgument("the camera's distance must be a positive, finite number of metres, got " +
                            python_float_repr(*view.distance));
    }
    camera.distance = *view.distance;
  }
  for (auto [setting, name, into] : {std::tuple{view.azimuth, "azimuth", &camera.azimuth},
                                     std::tuple{view.elevation, "elevation", &camera.elevation}}) {
    if (!setting) continue;
    if (!std::isfinite(*setting)) {
      throw InvalidArgument(std::string("the camera's ") + name + " must be a finite number of degrees, got " +
                            python_float_repr(*setting));
    }
    *into = *setting;
  }
  return camera;
}

// An endless plane we move under the camera, by geom id, with the step (m)
// it moves in: a quad's side, so that the picture does not shift.
struct EndlessPlane {
  int geom;
  mjtNum step;
};

// Each endless plane moved in its steps to lie under the camera (the
// scene's eye, between its two: there is one unless stereo).
void follow_camera(const std::vector<EndlessPlane>& planes, mjvScene& scene) {
  if (planes.empty()) return;
  float eye[3];
  for (int i = 0; i < 3; ++i) eye[i] = 0.5f * (scene.camera[0].pos[i] + scene.camera[1].pos[i]);
  for (int i = 0; i < scene.ngeom; ++i) {
    mjvGeom& geom = scene.geoms[i];
    if (geom.objtype != mjOBJ_GEOM) continue;
    for (const auto& plane : planes) {
      if (plane.geom != geom.objid) continue;
      const float to_eye[3] = {eye[0] - geom.pos[0], eye[1] - geom.pos[1], eye[2] - geom.pos[2]};
      const float step = static_cast<float>(plane.step);
      float shift[3] = {0, 0, 0};
      for (int side : {0, 1}) {
        const float axis[3] = {geom.mat[side], geom.mat[3 + side], geom.mat[6 + side]};  // a column of mat
        const float along = to_eye[0] * axis[0] + to_eye[1] * axis[1] + to_eye[2] * axis[2];
        const float moved = step * std::round(along / step);
        for (int j = 0; j < 3; ++j) shift[j] += moved * axis[j];
      }
      for (int j = 0; j < 3; ++j) geom.pos[j] += shift[j];
    }
  }
}

}  // namespace

void check_camera_view(const Model& model, const CameraView& view) { (void)camera_for(model.get(), nullptr, view); }

struct Renderer::Impl {
  Model model;
  int width;
  int height;
  std::shared_ptr<detail::OffscreenGl> gl = detail::OffscreenGl::shared();
  mjvScene scene;
  mjvOption option;
  mjrContext context;
  std::vector<std::uint8_t> rgb;  // as OpenGL reads them: rows from the bottom
  std::vector<float> depth;
  std::mutex mutex;
  RenderStyle style;
  std::vector<EndlessPlane> endless;  // (with a style's endless_planes)

  Impl(const Model& m, int w, int h, const RenderStyle& s) : model(m), width(w), height(h), style(s) {
    mjv_defaultScene(&scene);
    mjv_defaultOption(&option);
    mjr_defaultContext(&context);
  }
};

Renderer::Renderer(const Model& model, int width, int height, const RenderStyle& style) {
  check_size("width", width);
  check_size("height", height);
  if (style.shadow_size != 0 &&
      (style.shadow_size < RenderStyle::kMinShadowSize || style.shadow_size > RenderStyle::kMaxShadowSize)) {
    throw InvalidArgument("shadow_size must be " + std::to_string(RenderStyle::kMinShadowSize) + " to " +
                          std::to_string(RenderStyle::kMaxShadowSize) + " texels, or 0 for 2 a pixel, got " +
                          std::to_string(style.shadow_size));
  }
  detail::install_mujoco_handlers();
  impl_ = std::make_unique<Impl>(model, width, height, style);
  Impl& r = *impl_;
  const mjModel* m = model.get();
  // MuJoCo sizes its offscreen framebuffer (and its multisampled twin) by the
  // model's <visual><global offwidth offheight>, 640 x 480 unless the scene
  // says, and its shadow map by <quality shadowsize>, 4096 unless it says:
  // 86 MiB a renderer, whatever the picture's size. A shallow copy of the
  // model's struct, only ever read, asks for a buffer of the picture's size
  // (the same pixels: the picture is drawn in a viewport of that size) and a
  // shadow map of about 2 texels per pixel of the picture's larger side (at
  // least 512): a 4096 map's pass was a third of a 640 x 480 picture's time
  // on Mesa's software rasteriser, for shadow edges no sharper to the eye.
  mjModel sized = *m;
  sized.vis.global.offwidth = width;
  sized.vis.global.offheight = height;
  int shadow = style.shadow_size;
  if (shadow == 0) {
    shadow = 512;
    while (shadow < 2 * std::max(width, height) && shadow < m->vis.quality.shadowsize) shadow *= 2;
  }
  sized.vis.quality.shadowsize = std::min(m->vis.quality.shadowsize, shadow);
  if (!style.multisample) sized.vis.quality.offsamples = 0;
  // MuJoCo builds each plane's drawing with the context: a grid of quads,
  // lit at their corners, of the plane's size and its third size value's
  // spacing. A plane of no size it draws out to the far clipping plane in
  // mjMAXPLANEGRID (200) quads a side, moved under the camera for each
  // picture in whole repeats of its texture. Endless, a plane is drawn so;
  // without a material (no texture to repeat), in kEndlessPlaneGrid quads a
  // side that we move: on Mesa's software rasteriser 200 took 13 ms of a
  // 640 x 480 picture where 100 took 6, for a floor that looks the same.
  std::vector<mjtNum> geom_size(m->geom_size, m->geom_size + 3 * m->ngeom);
  if (style.endless_planes) {
    const mjtNum reach = m->vis.map.zfar * m->stat.extent;
    for (int g = 0; g < m->ngeom; ++g) {
      if (m->geom_type[g] != mjGEOM_PLANE) continue;
      mjtNum* size = geom_size.data() + 3 * g;
      if (m->geom_matid[g] >= 0) {
        size[0] = size[1] = 0;
        continue;
      }
      size[0] = size[1] = reach;
      size[2] = std::max(size[2], 2 * reach / kEndlessPlaneGrid);
      r.endless.push_back({g, size[2]});
    }
    sized.geom_size = geom_size.data();
  }
  r.gl->make_current();
  try {
    detail::mujoco_call([&] {
      mjv_makeScene(m, &r.scene, kMaxGeoms);
      mjr_makeContext(&sized, &r.context, mjFONTSCALE_100);
      mjr_setBuffer(mjFB_OFFSCREEN, &r.context);
    });
  } catch (const MujocoError& e) {
    mjv_freeScene(&r.scene);
    mjr_freeContext(&r.context);
    r.gl->release();
    // Out of memory (a ulimit -v) as much as a driver that lacks something.
    throw RenderError(std::string("MuJoCo could not set up a renderer: ") + e.what());
  }
  r.gl->release();
  r.rgb.resize(static_cast<std::size_t>(width) * height * 3);
  r.depth.resize(static_cast<std::size_t>(width) * height);
}

Renderer::~Renderer() {
  Impl& r = *impl_;
  try {
    r.gl->make_current();
    mjr_freeContext(&r.context);  // its textures and buffers live in the context
    r.gl->release();
  } catch (const RenderError&) {
    // The context is gone with the display; nothing of ours to free in it.
  }
  mjv_freeScene(&r.scene);
}

int Renderer::width() const noexcept { return impl_->width; }
int Renderer::height() const noexcept { return impl_->height; }

void Renderer::render(const Model& model, const mjData* d, const CameraView& view, std::uint8_t* rgb, float* depth) {
  Impl& r = *impl_;
  const mjModel* m = model.get();
  if (!same_structure(m, r.model.get())) {
    throw InvalidArgument("the state to draw is of another scene (" + model.source() + ") than the renderer's (" +
                          r.model.source() + ")");
  }
  mjvCamera camera = camera_for(m, d, view);
  const mjrRect viewport{0, 0, r.width, r.height};
  std::lock_guard<std::mutex> lock(r.mutex);
  r.gl->make_current();
  try {
    // mjv_updateScene takes mjData* but only reads the state (positions,
    // contacts, the lights' and cameras' frames), in every MuJoCo we build on.
    detail::mujoco_call([&] {
      mjv_updateScene(m, const_cast<mjData*>(d), &r.option, nullptr, &camera, mjCAT_ALL, &r.scene);
      follow_camera(r.endless, r.scene);
      mjr_setBuffer(mjFB_OFFSCREEN, &r.context);
      mjr_render(viewport, &r.scene, &r.context);
      mjr_readPixels(rgb ? r.rgb.data() : nullptr, depth ? r.depth.data() : nullptr, viewport, &r.context);
    });
  } catch (...) {
    r.gl->release();
    throw;
  }
  r.gl->release();
  const std::size_t w = static_cast<std::size_t>(r.width), h = static_cast<std::size_t>(r.height);
  // OpenGL's depth buffer holds 0..1, non-linear in distance: back to metres
  // with the near and far planes MuJoCo drew with.
  const mjModel* own = r.model.get();
  const double near = own->vis.map.znear * own->stat.extent, far = own->vis.map.zfar * own->stat.extent;
  for (std::size_t row = 0; row < h; ++row) {
    const std::size_t from = h - 1 - row;
    if (rgb) std::copy_n(r.rgb.data() + from * w * 3, w * 3, rgb + row * w * 3);
    if (depth) {
      const float* in = r.depth.data() + from * w;
      float* out = depth + row * w;
      for (std::size_t x = 0; x < w; ++x) out[x] = static_cast<float>(near / (1.0 - in[x] * (1.0 - near / far)));
    }
  }
}

}  // namespace simloop
