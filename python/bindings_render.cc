// simloop._core's Renderer: pictures of a Sim's or an episode's state as
// numpy arrays (simloop.Renderer and the Gymnasium envs' render()).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "bindings_common.hpp"
#include "bindings_sim.hpp"
#include "simloop/render.hpp"

namespace simloop_py {
namespace {

using namespace pybind11::literals;

// One picture of `d` (a state of `model`): (height, width, 3) uint8, or
// (height, width) float32 metres with depth. The GIL is released while
// MuJoCo draws; the caller holds whatever lock keeps `d` still.
py::array picture(simloop::Renderer& r, const simloop::Model& model, const mjData* d, const simloop::CameraView& view,
                  bool depth) {
  const auto h = static_cast<py::ssize_t>(r.height()), w = static_cast<py::ssize_t>(r.width());
  if (depth) {
    py::array_t<float> out({h, w});
    float* at = out.mutable_data();
    py::gil_scoped_release release;
    r.render(model, d, view, nullptr, at);
    return std::move(out);
  }
  py::array_t<std::uint8_t> out({h, w, py::ssize_t{3}});
  std::uint8_t* at = out.mutable_data();
  py::gil_scoped_release release;
  r.render(model, d, view, at, nullptr);
  return std::move(out);
}

}  // namespace

void bind_render(py::module_& m) {
  m.attr("MAX_PICTURE_SIZE") = simloop::Renderer::kMaxSize;
  py::class_<simloop::CameraView>(m, "CameraView", "Where a picture is taken from (include/simloop/render.hpp).")
      .def(py::init([](const std::optional<std::string>& camera, const std::optional<std::string>& track,
                       std::optional<double> distance, std::optional<double> azimuth, std::optional<double> elevation,
                       const std::optional<std::array<double, 3>>& lookat) {
             return simloop::CameraView{camera.value_or(""), track.value_or(""), lookat, distance, azimuth, elevation};
           }),
           "camera"_a, "track"_a, "distance"_a, "azimuth"_a, "elevation"_a, "lookat"_a = py::none());
  m.def("check_camera_view", &simloop::check_camera_view, "model"_a, "view"_a,
        "What a picture checks of its view, without drawing one.");
  py::class_<simloop::Renderer>(m, "Renderer", "Offscreen pictures of a scene's states (MuJoCo's renderer on EGL).")
      .def(py::init([](const simloop::Model& model, int width, int height, bool multisample, bool endless_planes,
                       int shadow_size) {
             return naming_failures("Renderer", [&] {
               return std::make_unique<simloop::Renderer>(
                   model, width, height, simloop::RenderStyle{multisample, endless_planes, shadow_size});
             });
           }),
           "model"_a, "width"_a, "height"_a, "multisample"_a = true, "endless_planes"_a = false, "shadow_size"_a = 0)
      .def_property_readonly("width", &simloop::Renderer::width)
      .def_property_readonly("height", &simloop::Renderer::height)
      .def(
          "render_sim",
          [](simloop::Renderer& r, PySim& s, const simloop::CameraView& view, bool depth) {
            SimLock lock(s);  // the state stays still while it is drawn
            return picture(r, s.sim.model(), s.sim.data(), view, depth);
          },
          "sim"_a, "view"_a, "depth"_a)
      .def(
          "render_episode",
          [](simloop::Renderer& r, PyEpisodes& e, std::size_t i, const simloop::CameraView& view, bool depth) {
            EpisodesLock lock(e);
            return picture(r, e.episodes.model(i), e.episodes.data(i), view, depth);
          },
          "episodes"_a, "i"_a, "view"_a, "depth"_a);
}

}  // namespace simloop_py
