#include "simloop/object_names.hpp"

#include <string>
#include <string_view>
#include <vector>

#include "mujoco_compat.hpp"
#include "simloop/errors.hpp"
#include "simloop/scenario.hpp"  // did_you_mean

namespace simloop {
namespace {

struct Kind {
  mjtObj type;
  const char* one;
  const char* many;
  const char* size;  // the mjModel size that counts them ("ngeom")
  int (*count)(const mjModel*);
};

#define SIMLOOP_KIND(type, one, many, size) \
  Kind { type, one, many, #size, [](const mjModel* m) { return detail::compat::as_int(m->size); } }
// The kinds of object a scene names, as Python spells them ("body", "geom").
const std::vector<Kind>& kinds() {
  static const std::vector<Kind> all{
      SIMLOOP_KIND(mjOBJ_BODY, "body", "bodies", nbody),
      SIMLOOP_KIND(mjOBJ_JOINT, "joint", "joints", njnt),
      SIMLOOP_KIND(mjOBJ_GEOM, "geom", "geoms", ngeom),
      SIMLOOP_KIND(mjOBJ_SITE, "site", "sites", nsite),
      SIMLOOP_KIND(mjOBJ_CAMERA, "camera", "cameras", ncam),
      SIMLOOP_KIND(mjOBJ_LIGHT, "light", "lights", nlight),
      SIMLOOP_KIND(mjOBJ_MESH, "mesh", "meshes", nmesh),
      SIMLOOP_KIND(mjOBJ_SKIN, "skin", "skins", nskin),
      SIMLOOP_KIND(mjOBJ_HFIELD, "hfield", "hfields", nhfield),
      SIMLOOP_KIND(mjOBJ_TEXTURE, "texture", "textures", ntex),
      SIMLOOP_KIND(mjOBJ_MATERIAL, "material", "materials", nmat),
      SIMLOOP_KIND(mjOBJ_PAIR, "pair", "pairs", npair),
      SIMLOOP_KIND(mjOBJ_EXCLUDE, "exclude", "excludes", nexclude),
      SIMLOOP_KIND(mjOBJ_EQUALITY, "equality", "equalities", neq),
      SIMLOOP_KIND(mjOBJ_TENDON, "tendon", "tendons", ntendon),
      SIMLOOP_KIND(mjOBJ_ACTUATOR, "actuator", "actuators", nu),
      SIMLOOP_KIND(mjOBJ_SENSOR, "sensor", "sensors", nsensor),
      SIMLOOP_KIND(mjOBJ_NUMERIC, "numeric", "numerics", nnumeric),
      SIMLOOP_KIND(mjOBJ_TEXT, "text", "texts", ntext),
      SIMLOOP_KIND(mjOBJ_TUPLE, "tuple", "tuples", ntuple),
      SIMLOOP_KIND(mjOBJ_KEY, "keyframe", "keyframes", nkey),
  };
  return all;
}
#undef SIMLOOP_KIND

const Kind& kind_of(mjtObj type) {
  for (const Kind& k : kinds()) {
    if (k.type == type) return k;
  }
  throw InvalidArgument("objects of MuJoCo type " + std::to_string(type) + " are not looked up by name");
}

// "the scene's joints: hip, knee (and 2 unnamed)": what a lookup could have named.
std::string listing(const mjModel* m, mjtObj type, std::vector<std::string>& names) {
  const int count = object_count(m, type);
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

mjtObj object_type_named(std::string_view kind) noexcept {
  for (const Kind& k : kinds()) {
    if (kind == k.one) return k.type;
  }
  return mjOBJ_UNKNOWN;
}

const std::vector<std::string>& object_kinds() {
  static const std::vector<std::string> words = [] {
    std::vector<std::string> out;
    for (const Kind& k : kinds()) out.emplace_back(k.one);
    return out;
  }();
  return words;
}

const char* object_kind(mjtObj type) { return kind_of(type).one; }

mjtObj object_type_counted_by(std::string_view size) noexcept {
  for (const Kind& k : kinds()) {
    if (size == k.size) return k.type;
  }
  return mjOBJ_UNKNOWN;
}

int object_count(const mjModel* m, mjtObj type) { return kind_of(type).count(m); }

std::vector<std::string> object_names(const mjModel* m, mjtObj type) {
  std::vector<std::string> names(static_cast<std::size_t>(object_count(m, type)));
  for (std::size_t i = 0; i < names.size(); ++i) {
    const char* name = mj_id2name(m, type, static_cast<int>(i));
    if (name != nullptr) names[i] = name;
  }
  return names;
}

JointSize joint_size(int type) noexcept {
  if (type == mjJNT_FREE) return {7, 6};
  if (type == mjJNT_BALL) return {4, 3};
  return {1, 1};
}

const char* joint_type_name(int type) noexcept {
  switch (type) {
    case mjJNT_FREE: return "free";
    case mjJNT_BALL: return "ball";
    case mjJNT_SLIDE: return "slide";
    case mjJNT_HINGE: return "hinge";
    default: return "unknown";
  }
}

int object_id(const mjModel* m, mjtObj type, const std::string& name) {
  (void)object_count(m, type);  // a type we look up
  const int found = mj_name2id(m, type, name.c_str());
  if (found >= 0) return found;
  std::vector<std::string> names;
  const std::string known = listing(m, type, names);
  const std::string hint = did_you_mean(name, names);
  throw InvalidArgument(std::string("no ") + kind_of(type).one + " named '" + name + "'" +
                        (hint.empty() ? "" : " (did you mean '" + hint + "'?)") + "; " + known);
}

int checked_object_index(const mjModel* m, mjtObj type, long long index) {
  const int count = object_count(m, type);
  if (index >= 0 && index < count) return static_cast<int>(index);
  std::vector<std::string> names;
  throw InvalidArgument(std::string(kind_of(type).one) + " index " + std::to_string(index) +
                        " is out of range: the scene has " + std::to_string(count) + " " +
                        (count == 1 ? kind_of(type).one : kind_of(type).many) +
                        (count > 0 ? "; " + listing(m, type, names) : std::string()));
}

}  // namespace simloop
