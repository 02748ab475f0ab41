// scene_geometry: the scene's own shapes, for the recording: every visible
// geom with its shape and colour, meshes as their bounding boxes.
#include "simloop/scene_geometry.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "simloop/chapter_scene.hpp"
#include "simloop/model.hpp"

namespace {

TEST(SceneGeometry, ListsEveryVisibleGeomWithItsShapeAndColour) {
  const simloop::Model scene = simloop::Model::from_file(std::string(SIMLOOP_TEST_SCENES) + "/pusht.xml");
  const std::vector<simloop::GeomShape> shapes = simloop::scene_geometry(scene.get());
  ASSERT_EQ(shapes.size(), 5u);  // floor, goal, the T's two bars, the tip
  EXPECT_EQ(shapes[0].name, "floor");
  EXPECT_EQ(shapes[0].body, "world");
  EXPECT_EQ(shapes[0].kind, simloop::GeomShape::Kind::kPlane);
  EXPECT_EQ(shapes[2].name, "t_bar");
  EXPECT_EQ(shapes[2].body, "tblock");
  EXPECT_EQ(shapes[2].kind, simloop::GeomShape::Kind::kBox);
  EXPECT_EQ(shapes[2].half_size, (std::array<double, 3>{0.08, 0.02, 0.02}));
  EXPECT_EQ(shapes[2].pos, (std::array<double, 3>{0.0, 0.03, 0.0}));
  EXPECT_EQ(shapes[2].rgba, (std::array<float, 4>{0.8f, 0.5f, 0.2f, 1.0f}));
  EXPECT_EQ(shapes[4].kind, simloop::GeomShape::Kind::kCylinder);
  EXPECT_EQ(shapes[4].half_size, (std::array<double, 3>{0.015, 0.015, 0.02}));
  EXPECT_FLOAT_EQ(shapes[1].rgba[3], 0.4f);  // the goal is see-through
}

TEST(SceneGeometry, MeshesAreTheirBoundingBoxesAndMaterialsGiveColour) {
  (void)simloop::pusher_scene();
  const char* xml = R"(<mujoco>
    <asset>
      <mesh name="wedge" vertex="0 0 0  1 0 0  0 2 0  0 0 3"/>
      <material name="blue" rgba="0 0 1 1"/>
    </asset>
    <worldbody>
      <body name="b"><freejoint/><geom name="w" type="mesh" mesh="wedge" material="blue"/></body>
      <geom name="hidden" type="sphere" size="1" group="3"/>
      <geom name="clear" type="sphere" size="1" rgba="1 0 0 0"/>
    </worldbody></mujoco>)";
  const simloop::Model model = simloop::Model::from_xml_string(xml, "wedge scene");
  const mjModel* m = model.get();
  const std::vector<simloop::GeomShape> shapes = simloop::scene_geometry(m);
  ASSERT_EQ(shapes.size(), 1u);
  EXPECT_EQ(shapes[0].kind, simloop::GeomShape::Kind::kMesh);
  // MuJoCo moves a mesh to its centre of mass and principal axes (the geom's
  // pos and quat); the vertices as written, brought into the geom's frame,
  // lie inside the box, and some touch each face.
  const simloop::GeomShape& w = shapes[0];
  double touching = 0;
  for (const auto& v : std::vector<std::array<double, 3>>{{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, 3}}) {
    double offset[3] = {v[0] - w.pos[0], v[1] - w.pos[1], v[2] - w.pos[2]}, local[3];
    double inverse[4] = {w.quat[0], -w.quat[1], -w.quat[2], -w.quat[3]};
    mju_rotVecQuat(local, offset, inverse);
    for (int i = 0; i < 3; ++i) {
      const double from_centre = std::fabs(local[i] - w.mesh_center[static_cast<size_t>(i)]);
      EXPECT_LE(from_centre, w.half_size[static_cast<size_t>(i)] + 1e-5);
      if (from_centre > w.half_size[static_cast<size_t>(i)] - 1e-5) ++touching;
    }
  }
  EXPECT_GE(touching, 6);
  EXPECT_EQ(shapes[0].rgba, (std::array<float, 4>{0.0f, 0.0f, 1.0f, 1.0f}));
}

}  // namespace
