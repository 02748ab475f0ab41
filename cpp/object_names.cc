#include "simloop/object_names.hpp"

#include <string>
#include <vector>

#include "mujoco_compat.hpp"
#include "simloop/errors.hpp"
#include "simloop/scenario.hpp"  // did_you_mean

namespace simloop {
namespace {

struct Kind {
  const char* one;
  const char* many;
};

Kind kind_of(mjtObj type) {
  switch (type) {
    case mjOBJ_BODY: return {"body", "bodies"};
    case mjOBJ_JOINT: return {"joint", "joints"};
    case mjOBJ_ACTUATOR: return {"actuator", "actuators"};
    case mjOBJ_SENSOR: return {"sensor", "sensors"};
    case mjOBJ_KEY: return {"keyframe", "keyframes"};
    case mjOBJ_GEOM: return {"geom", "geoms"};
    case mjOBJ_SITE: return {"site", "sites"};
    case mjOBJ_CAMERA: return {"camera", "cameras"};
    default: return {"object", "objects"};
  }
}

int count_of(const mjModel* m, mjtObj type) {
  switch (type) {
    case mjOBJ_BODY: return detail::compat::as_int(m->nbody);
    case mjOBJ_JOINT: return detail::compat::as_int(m->njnt);
    case mjOBJ_ACTUATOR: return detail::compat::as_int(m->nu);
    case mjOBJ_SENSOR: return detail::compat::as_int(m->nsensor);
    case mjOBJ_KEY: return detail::compat::as_int(m->nkey);
    case mjOBJ_GEOM: return detail::compat::as_int(m->ngeom);
    case mjOBJ_SITE: return detail::compat::as_int(m->nsite);
    case mjOBJ_CAMERA: return detail::compat::as_int(m->ncam);
    default: throw InvalidArgument("objects of MuJoCo type " + std::to_string(type) + " are not looked up by name");
  }
}

// "the scene's joints: hip, knee (and 2 unnamed)": what a lookup could have named.
std::string listing(const mjModel* m, mjtObj type, std::vector<std::string>& names) {
  const int count = count_of(m, type);
  int unnamed = 0;
  for (int i = 0; i < count; ++i) {
    const char* name = mj_id2name(m, type, i);
    if (name != nullptr && *name != '\0') {
      names.emplace_back(name);
    } else {
      ++unnamed;
    }
  }
  if (count == 0) return std::string("the scene has no ") + kind_of(type).many;
  std::string out = std::string("the scene's ") + kind_of(type).many + ": ";
  if (names.empty()) out += "(none named)";
  for (std::size_t i = 0; i < names.size(); ++i) out += (i ? ", " : "") + names[i];
  if (unnamed > 0 && !names.empty()) out += " (and " + std::to_string(unnamed) + " unnamed)";
  if (unnamed > 0) out += "; " + std::to_string(count) + " in all, by index 0 to " + std::to_string(count - 1);
  return out;
}

}  // namespace

int object_id(const mjModel* m, mjtObj type, const std::string& name) {
  (void)count_of(m, type);  // a type we look up
  const int found = mj_name2id(m, type, name.c_str());
  if (found >= 0) return found;
  std::vector<std::string> names;
  const std::string known = listing(m, type, names);
  const std::string hint = did_you_mean(name, names);
  throw InvalidArgument(std::string("no ") + kind_of(type).one + " named '" + name + "'" +
                        (hint.empty() ? "" : " (did you mean '" + hint + "'?)") + "; " + known);
}

int checked_object_index(const mjModel* m, mjtObj type, long long index) {
  const int count = count_of(m, type);
  if (index >= 0 && index < count) return static_cast<int>(index);
  std::vector<std::string> names;
  throw InvalidArgument(std::string(kind_of(type).one) + " index " + std::to_string(index) +
                        " is out of range: the scene has " + std::to_string(count) + " " +
                        (count == 1 ? kind_of(type).one : kind_of(type).many) +
                        (count > 0 ? "; " + listing(m, type, names) : std::string()));
}

}  // namespace simloop
