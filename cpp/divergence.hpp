// simloop's own divergence check (internal to the library).
//
// A blow-up often raises no MuJoCo warning: at --timestep 1 the box falls
// through the floor, is flung kilometres away and the run ends "fine". The
// check watches each free body (a body on a free joint: what can fly off)
// against the floor, the highest upward-facing plane of the world body:
//
//   a free body has diverged when its centre gets more than
//   kDivergedDepthInSizes (10) times its own size below the floor, its size
//   being the diameter of the sphere around all its geoms.
//
// For the chapter's box (half-side 0.05 m, size 0.173 m) the line is
// z = -1.73 m. Measured over seeds 0-20 (lowest centre z reached): the
// chapter's 0.002 s stays above -0.001 m; Break It, 0.05 s, is visibly wrong
// but dips at most to -0.5 m (seed 0: -0.17 m), 3.5 times above the line;
// 0.1 s reaches -0.2 to -3.1 m (some seeds trip); 1 s reaches -64 to -345 m
// and 5 s -800 to -5800 m, all 37 times or more below it. Scenes without such
// a plane, or without free bodies, are not checked. Non-finite states are
// MuJoCo's own warnings (mjWARN_BADQPOS etc.), already reported. Energy is
// no separate sign here: the energy audit explains even the 5 s run's
// +1.8 MJ (the shove's and the contacts' work grow with the speeds; 2.7 kJ
// is left unexplained), so "energy beyond the work done" would not catch it.
//
// It costs one comparison per free body per step.
#pragma once

#include <mujoco/mujoco.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "simloop/rows.hpp"

namespace simloop::detail {

inline constexpr const char* kDivergedWarning = "simloop_DIVERGED";
inline constexpr double kDivergedDepthInSizes = 10.0;

class DivergenceCheck {
 public:
  explicit DivergenceCheck(const mjModel* m) {
    bool have_floor = false;
    for (int g = 0; g < m->ngeom; ++g) {
      if (m->geom_bodyid[g] != 0 || m->geom_type[g] != mjGEOM_PLANE) continue;
      // The plane's normal is its frame's z axis: world z of the rotated (0, 0, 1).
      const double* q = m->geom_quat + 4 * g;
      const double normal_z = q[0] * q[0] - q[1] * q[1] - q[2] * q[2] + q[3] * q[3];
      if (normal_z < 0.999) continue;
      const double z = m->geom_pos[3 * g + 2];
      if (!have_floor || z > floor_z_) floor_z_ = z;
      have_floor = true;
    }
    if (!have_floor) return;
    for (int j = 0; j < m->njnt; ++j) {
      if (m->jnt_type[j] != mjJNT_FREE) continue;
      const int body = m->jnt_bodyid[j];
      double radius = 0.0;
      for (int g = 0; g < m->ngeom; ++g) {
        if (m->geom_bodyid[g] != body) continue;
        const double* p = m->geom_pos + 3 * g;
        radius = std::fmax(radius, std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) + m->geom_rbound[g]);
      }
      if (radius <= 0.0) continue;
      const char* name = mj_id2name(m, mjOBJ_BODY, body);
      bodies_.push_back({m->jnt_qposadr[j] + 2, floor_z_ - kDivergedDepthInSizes * 2.0 * radius, radius,
                         name ? std::string(name) : "body " + std::to_string(body)});
    }
  }

  // After each step: one comparison per free body.
  void after_step(const mjData* d, std::int64_t step) noexcept {
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      const double z = d->qpos[bodies_[i].z_adr];
      if (!(z < bodies_[i].limit_z)) continue;
      if (count_ == 0) {
        first_step_ = step;
        first_body_ = i;
      }
      ++count_;
      if (i == first_body_ && z < lowest_z_) lowest_z_ = z;
    }
  }

  // The warning to add to the run's, if any body diverged.
  [[nodiscard]] bool diverged() const noexcept { return count_ > 0; }
  [[nodiscard]] Warning warning() const {
    const Body& first = bodies_[first_body_];
    char text[400];
    std::snprintf(text, sizeof text,
                  "body \"%s\" went through the floor: its centre reached z = %.6g m, more than %g times its size "
                  "(%.3g m) below the floor (z = %.6g m); the simulation diverged (too large a timestep?)",
                  first.name.c_str(), lowest_z_, kDivergedDepthInSizes, 2.0 * first.radius, floor_z_);
    return Warning{kDivergedWarning, count_, first_step_, text};
  }

 private:
  struct Body {
    int z_adr;       // qpos index of the free joint's z
    double limit_z;  // below this, diverged
    double radius;   // of the sphere around its geoms
    std::string name;
  };
  std::vector<Body> bodies_;
  double floor_z_ = 0.0;
  std::int64_t count_ = 0;  // steps that ended with a body past its line
  std::int64_t first_step_ = 0;
  std::size_t first_body_ = 0;  // an index, not a pointer: a copy (Sim's) keeps its own
  double lowest_z_ = INFINITY;
};

}  // namespace simloop::detail
