// Renderer: pictures of the chapter's scene put each body where it is, the
// depth is in metres, and every bad view or size is refused naming it.
#include "simloop/render.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "simloop/chapter_scene.hpp"
#include "simloop/errors.hpp"
#include "simloop/sim.hpp"
#include "test_util.hpp"

namespace {

constexpr int kWidth = 160;
constexpr int kHeight = 120;

struct Picture {
  std::vector<std::uint8_t> rgb = std::vector<std::uint8_t>(kWidth * kHeight * 3);
  std::vector<float> depth = std::vector<float>(kWidth * kHeight);
  [[nodiscard]] const std::uint8_t* at(int x, int y) const { return rgb.data() + (y * kWidth + x) * 3; }
  // The box is red (0.85, 0.3, 0.25), the pusher blue (0.25, 0.45, 0.85),
  // the floor grey: each channel lit and shaded, the ratios kept.
  [[nodiscard]] bool red(int x, int y) const { return at(x, y)[0] > 2 * at(x, y)[1] && at(x, y)[0] > 2 * at(x, y)[2]; }
  [[nodiscard]] bool blue(int x, int y) const { return at(x, y)[2] > 2 * at(x, y)[0] && at(x, y)[2] > at(x, y)[1]; }
  // The mean column of the pixels that pass `is`, or -1 if none do.
  template <class Is>
  [[nodiscard]] double mean_column(Is is) const {
    double sum = 0;
    int count = 0;
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        if (is(x, y)) sum += x, ++count;
      }
    }
    return count ? sum / count : -1.0;
  }
};

Picture draw(simloop::Renderer& renderer, const simloop::Sim& sim, const simloop::CameraView& view) {
  Picture p;
  renderer.render(sim.model(), sim.data(), view, p.rgb.data(), p.depth.data());
  return p;
}

simloop::CameraView looking_at(const std::string& body) {
  simloop::CameraView view;
  view.track = body;
  return view;
}

TEST(Renderer, ThePictureOfTheChaptersSceneAtRestHasTheBoxWhereTheBoxIs) {
  const simloop::Model model = simloop::pusher_scene();
  const simloop::Sim sim(model);  // t = 0, as mj_forward leaves it
  simloop::Renderer renderer(model, kWidth, kHeight);
  const Picture on_box = draw(renderer, sim, looking_at("box"));
  EXPECT_TRUE(on_box.red(kWidth / 2, kHeight / 2));
  EXPECT_FALSE(on_box.blue(kWidth / 2, kHeight / 2));
  const Picture on_pusher = draw(renderer, sim, looking_at("pusher"));
  EXPECT_TRUE(on_pusher.blue(kWidth / 2, kHeight / 2));
  // The default free camera looks along +y (azimuth 90): x grows to the
  // right, and the box (x = 0.4) stands right of the pusher (x = 0).
  const Picture whole = draw(renderer, sim, simloop::CameraView{});
  const double box_column = whole.mean_column([&](int x, int y) { return whole.red(x, y); });
  const double pusher_column = whole.mean_column([&](int x, int y) { return whole.blue(x, y); });
  ASSERT_GE(box_column, 0);
  ASSERT_GE(pusher_column, 0);
  EXPECT_GT(box_column, pusher_column + kWidth / 10);
}

TEST(Renderer, TheBoxMovesInThePictureAsItMovesInTheScene) {
  const simloop::Model model = simloop::pusher_scene();
  simloop::Sim sim(model);
  simloop::Renderer renderer(model, kWidth, kHeight);
  simloop::CameraView view = looking_at("pusher");
  view.distance = 1.5;
  const Picture at_rest = draw(renderer, sim, view);
  sim.data()->qpos[0] -= 0.3;  // the box 0.3 m towards -x, past the pusher's left
  sim.forward();
  const Picture moved = draw(renderer, sim, view);
  const double rest_column = at_rest.mean_column([&](int x, int y) { return at_rest.red(x, y); });
  const double moved_column = moved.mean_column([&](int x, int y) { return moved.red(x, y); });
  ASSERT_GE(rest_column, 0);
  ASSERT_GE(moved_column, 0);
  EXPECT_LT(moved_column, rest_column - kWidth / 10);
}

TEST(Renderer, DepthIsMetresFromTheCamerasPlane) {
  const simloop::Model model = simloop::pusher_scene();
  const simloop::Sim sim(model);
  simloop::Renderer renderer(model, kWidth, kHeight);
  simloop::CameraView view = looking_at("box");
  view.distance = 1.0;
  view.elevation = -90.0;  // straight down onto the box's top face
  const Picture p = draw(renderer, sim, view);
  // The camera is 1 m above the box's centre, its top face 0.05 m above that.
  EXPECT_NEAR(p.depth[(kHeight / 2) * kWidth + kWidth / 2], 0.95, 0.01);
  // The floor is 1.05 m below the camera: nothing in a corner is nearer.
  EXPECT_GT(p.depth[0], 1.04);
}

TEST(Renderer, TheSameStateGivesTheSamePicture) {
  const simloop::Model model = simloop::pusher_scene();
  const simloop::Sim sim(model);
  simloop::Renderer renderer(model, kWidth, kHeight);
  const Picture first = draw(renderer, sim, looking_at("box"));
  const Picture second = draw(renderer, sim, looking_at("box"));
  EXPECT_EQ(first.rgb, second.rgb);
  EXPECT_EQ(first.depth, second.depth);
}

TEST(Renderer, OneRendererDrawsForManyThreadsInTurn) {
  const simloop::Model model = simloop::pusher_scene();
  const simloop::Sim sim(model);
  simloop::Renderer renderer(model, kWidth, kHeight);
  const Picture alone = draw(renderer, sim, looking_at("box"));
  std::vector<Picture> pictures(4);
  std::vector<std::thread> threads;
  for (Picture& p : pictures) {
    threads.emplace_back([&] { renderer.render(model, sim.data(), looking_at("box"), p.rgb.data(), nullptr); });
  }
  for (std::thread& t : threads) t.join();
  for (const Picture& p : pictures) EXPECT_EQ(p.rgb, alone.rgb);
}

TEST(Renderer, BadSizesAndViewsAreRefusedNamingThem) {
  const simloop::Model model = simloop::pusher_scene();
  EXPECT_EQ(test::error_of([&] { simloop::Renderer(model, 0, 10); }),
            "the picture's width must be from 1 to 8192 pixels, got 0");
  EXPECT_EQ(test::error_of([&] { simloop::Renderer(model, 10, 8193); }),
            "the picture's height must be from 1 to 8192 pixels, got 8193");
  const auto refused = [&](simloop::CameraView view) {
    return test::error_of([&] { simloop::check_camera_view(model, view); });
  };
  simloop::CameraView camera;
  camera.camera = "top";
  EXPECT_EQ(refused(camera), "no camera named 'top'; the scene has no cameras");
  EXPECT_EQ(refused(looking_at("boxx")),
            "no body named 'boxx' (did you mean 'box'?); the scene's bodies: world, box, pusher");
  simloop::CameraView both = looking_at("box");
  both.camera = "top";
  EXPECT_EQ(refused(both),
            "a picture is taken from a scene's camera ('top') or a free camera looking at a body ('box'), not both");
  simloop::CameraView point = camera;
  point.lookat = std::array<double, 3>{0.0, 0.0, 0.0};
  EXPECT_EQ(refused(point),
            "a picture is taken from a scene's camera ('top') or a free camera looking at a point, not both");
  point.camera.clear();
  point.track = "box";
  EXPECT_EQ(refused(point), "a free camera looks at a body ('box') or at a point, not both");
  point.track.clear();
  point.lookat = std::array<double, 3>{0.0, std::numeric_limits<double>::quiet_NaN(), 0.0};
  EXPECT_EQ(refused(point), "the camera's lookat must be 3 finite numbers of metres, got nan");
  simloop::RenderStyle style;
  style.shadow_size = 63;
  try {
    simloop::Renderer too_fine(model, kWidth, kHeight, style);
    ADD_FAILURE() << "a shadow map of 63 texels was taken";
  } catch (const simloop::InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "shadow_size must be 64 to 16384 texels, or 0 for 2 a pixel, got 63");
  }
  camera.distance = 2.0;
  EXPECT_EQ(refused(camera), "camera 'top' is the scene's own: distance, azimuth and elevation are for a free camera");
  simloop::CameraView far;
  far.distance = 0.0;
  EXPECT_EQ(refused(far), "the camera's distance must be a positive, finite number of metres, got 0.0");
  simloop::CameraView turned;
  turned.azimuth = std::numeric_limits<double>::infinity();
  EXPECT_EQ(refused(turned), "the camera's azimuth must be a finite number of degrees, got inf");
  EXPECT_EQ(refused(simloop::CameraView{}), test::kNoInvalidArgument);

  simloop::Renderer renderer(model, kWidth, kHeight);
  const simloop::Model other = simloop::Model::from_xml_string(
      "<mujoco><worldbody><body><freejoint/><geom size='0.1'/></body></worldbody></mujoco>", "a ball");
  const simloop::Sim ball(other);
  Picture p;
  EXPECT_EQ(test::error_of([&] { renderer.render(other, ball.data(), {}, p.rgb.data(), nullptr); }),
            "the state to draw is of another scene (a ball) than the renderer's (pusher scene)");
}

}  // namespace
