#include "simloop/scene_geometry.hpp"

#include <algorithm>
#include <limits>

#include "simloop/object_names.hpp"

namespace simloop {
namespace {

GeomShape::Kind kind_of(int type) {
  switch (type) {
    case mjGEOM_PLANE:
      return GeomShape::Kind::kPlane;
    case mjGEOM_SPHERE:
      return GeomShape::Kind::kSphere;
    case mjGEOM_CAPSULE:
      return GeomShape::Kind::kCapsule;
    case mjGEOM_ELLIPSOID:
      return GeomShape::Kind::kEllipsoid;
    case mjGEOM_CYLINDER:
      return GeomShape::Kind::kCylinder;
    case mjGEOM_BOX:
      return GeomShape::Kind::kBox;
    case mjGEOM_MESH:
      return GeomShape::Kind::kMesh;
    default:
      return GeomShape::Kind::kOther;
  }
}

// MuJoCo's default geom colour: a geom left at it shows its material's.
constexpr float kDefaultRgba[4] = {0.5f, 0.5f, 0.5f, 1.0f};

}  // namespace

std::vector<GeomShape> scene_geometry(const mjModel* m) {
  std::vector<GeomShape> out;
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_group[g] > 2) continue;  // hidden by default in MuJoCo's viewer
    GeomShape s;
    s.name = object_name(m, mjOBJ_GEOM, g);
    s.body_id = m->geom_bodyid[g];
    s.body = object_name(m, mjOBJ_BODY, s.body_id);
    s.kind = kind_of(m->geom_type[g]);
    const mjtNum* size = m->geom_size + 3 * g;
    switch (s.kind) {
      case GeomShape::Kind::kSphere:
        s.half_size = {size[0], size[0], size[0]};
        break;
      case GeomShape::Kind::kCapsule:
      case GeomShape::Kind::kCylinder:
        s.half_size = {size[0], size[0], size[1]};
        break;
      case GeomShape::Kind::kPlane:
        s.half_size = {size[0] > 0 ? size[0] : 1.0, size[1] > 0 ? size[1] : 1.0, 0.0};
        break;
      case GeomShape::Kind::kMesh: {
        const int mesh = m->geom_dataid[g];
        std::array<double, 3> low{}, high{};
        low.fill(std::numeric_limits<double>::infinity());
        high.fill(-std::numeric_limits<double>::infinity());
        for (int v = 0; v < m->mesh_vertnum[mesh]; ++v) {
          const float* p = m->mesh_vert + 3 * (m->mesh_vertadr[mesh] + v);
          for (int i = 0; i < 3; ++i) {
            low[static_cast<size_t>(i)] = std::min(low[static_cast<size_t>(i)], static_cast<double>(p[i]));
            high[static_cast<size_t>(i)] = std::max(high[static_cast<size_t>(i)], static_cast<double>(p[i]));
          }
        }
        if (m->mesh_vertnum[mesh] > 0) {
          for (size_t i = 0; i < 3; ++i) {
            s.half_size[i] = (high[i] - low[i]) / 2;
            s.mesh_center[i] = (high[i] + low[i]) / 2;
          }
        }
        break;
      }
      default:
        s.half_size = {size[0], size[1], size[2]};
        break;
    }
    std::copy(m->geom_pos + 3 * g, m->geom_pos + 3 * g + 3, s.pos.begin());
    std::copy(m->geom_quat + 4 * g, m->geom_quat + 4 * g + 4, s.quat.begin());
    const float* rgba = m->geom_rgba + 4 * g;
    const bool default_colour = std::equal(rgba, rgba + 4, kDefaultRgba);
    if (m->geom_matid[g] >= 0 && default_colour) rgba = m->mat_rgba + 4 * m->geom_matid[g];
    std::copy(rgba, rgba + 4, s.rgba.begin());
    if (s.rgba[3] <= 0.0f) continue;  // fully transparent: nothing to see
    out.push_back(s);
  }
  return out;
}

}  // namespace simloop
