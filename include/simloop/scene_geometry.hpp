// The scene's own shapes, for drawing it (the rerun recording): what each
// visible geom is, where it sits on its body, and its colour.
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <string>
#include <vector>

namespace simloop {

struct GeomShape {
  enum class Kind { kPlane, kSphere, kCapsule, kEllipsoid, kCylinder, kBox, kMesh, kOther };
  std::string name;  // the geom's name, or "geom<id>"
  std::string body;  // its body's name, or "body<id>" ("world" for the world body)
  int body_id = 0;
  Kind kind = Kind::kOther;
  // Half sizes along the geom's own x, y, z, m: a box's half extents; a
  // sphere's radius (x3); an ellipsoid's radii; a capsule's or cylinder's
  // radius, radius, half length (along z); a plane's half extents (0 = infinite,
  // drawn as 1 m), z 0; a mesh's bounding box around `mesh_center`.
  std::array<double, 3> half_size{};
  std::array<double, 3> mesh_center{};     // meshes: the bounding box's centre, geom frame
  std::array<double, 3> pos{};             // geom frame in its body's frame
  std::array<double, 4> quat{1, 0, 0, 0};  // w, x, y, z
  std::array<float, 4> rgba{};             // the geom's colour, or its material's
};

// Every geom a viewer shows by default (groups 0 to 2, not fully
// transparent), in geom order.
[[nodiscard]] std::vector<GeomShape> scene_geometry(const mjModel* m);

}  // namespace simloop
