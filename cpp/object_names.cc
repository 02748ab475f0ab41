#include "simloop/object_names.hpp"

#include <algorithm>
#include <cctype>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "mujoco_compat.hpp"
#include "simloop/errors.hpp"

namespace simloop {
namespace {

struct Kind {
  mjtObj type;
  const char* one;
  const char* many;
  const char* size;  // the mjModel size that counts them ("ngeom")
  int (*count)(const mjModel*);
};

#define SIMLOOP_KIND(type, one, many, size)                                                  \
  Kind {                                                                                     \
    type, one, many, #size, [](const mjModel* m) { return detail::compat::as_int(m->size); } \
  }
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

}  // namespace

mjtObj object_type_named(std::string_view kind) noexcept {
  for (const Kind& k : kinds()) {
    if (kind == k.one) return k.type;
  }
  return mjOBJ_UNKNOWN;
}

mjtObj object_type_of_kind(std::string_view kind) {
  const mjtObj type = object_type_named(kind);
  if (type != mjOBJ_UNKNOWN) return type;
  std::string words;
  for (const std::string& k : object_kinds()) words += (words.empty() ? "'" : ", '") + k + "'";
  throw InvalidArgument("kind must be one of " + words + ", got '" + std::string(kind) + "'");
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

std::string object_name(const mjModel* m, mjtObj type, int id) {
  const char* name = mj_id2name(m, type, id);
  if (name && *name) return name;
  if (type == mjOBJ_BODY && id == 0) return "world";
  return kind_of(type).one + std::to_string(id);
}

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
    case mjJNT_FREE:
      return "free";
    case mjJNT_BALL:
      return "ball";
    case mjJNT_SLIDE:
      return "slide";
    case mjJNT_HINGE:
      return "hinge";
    default:
      return "unknown";
  }
}

// Walked up the tree rather than read from body_weldid: MuJoCo 2.2 welds a
// mocap body to the world, later versions to itself.
bool body_can_move(const mjModel* m, int body) {
  for (; body > 0; body = m->body_parentid[body]) {
    if (m->body_dofnum[body] > 0 || m->body_mocapid[body] >= 0) return true;
  }
  return false;
}

bool body_can_be_pushed(const mjModel* m, int body) {
  for (; body > 0; body = m->body_parentid[body]) {
    if (m->body_dofnum[body] > 0) return true;
  }
  return false;
}

// "the scene's joints: hip, knee; unnamed, by index: 0, 3 to 5", or "the
// scene has no joints": what a lookup could have named.
std::string object_listing(const mjModel* m, mjtObj type, ObjectFilter listed) {
  const int count = object_count(m, type);
  const std::string what = listed.what ? listed.what : kind_of(type).many;
  std::string named, unnamed;
  int run_start = -1;  // a run of consecutive unnamed indices, shown as "3 to 5"
  const auto end_run = [&](int last) {
    if (run_start < 0) return;
    unnamed += (unnamed.empty() ? "" : ", ") + std::to_string(run_start);
    if (last > run_start + 1) unnamed += " to " + std::to_string(last);
    if (last == run_start + 1) unnamed += ", " + std::to_string(last);
    run_start = -1;
  };
  for (int i = 0; i < count; ++i) {
    if (listed.keep && !listed.keep(m, i)) {
      end_run(i - 1);
      continue;
    }
    const char* name = mj_id2name(m, type, i);
    if (name != nullptr && *name != '\0') {
      end_run(i - 1);
      named += (named.empty() ? "" : ", ") + std::string(name);
    } else if (run_start < 0) {
      run_start = i;
    }
  }
  end_run(count - 1);
  if (named.empty() && unnamed.empty()) return "the scene has no " + what;
  return "the scene's " + what + ": " + named + (named.empty() || unnamed.empty() ? "" : "; ") +
         (unnamed.empty() ? "" : "unnamed, by index: " + unnamed);
}

std::string unknown_name_message(const mjModel* m, mjtObj type, const std::string& name, ObjectFilter listed) {
  std::vector<std::string> names = object_names(m, type);
  names.erase(std::remove(names.begin(), names.end(), std::string()), names.end());
  const std::string hint = did_you_mean(name, names);
  return std::string("no ") + kind_of(type).one + " named '" + name + "'" +
         (hint.empty() ? "" : " (did you mean '" + hint + "'?)") + "; " + object_listing(m, type, listed);
}

std::string index_out_of_range_message(const mjModel* m, mjtObj type, const std::string& index, ObjectFilter listed) {
  const int count = object_count(m, type);
  const Kind& kind = kind_of(type);
  if (count == 0) return std::string(kind.one) + " index " + index + " is out of range: the scene has no " + kind.many;
  return std::string(kind.one) + " index " + index + " is out of range: the scene has " + std::to_string(count) + " " +
         (count == 1 ? kind.one : kind.many) + " (0 to " + std::to_string(count - 1) + "); " +
         object_listing(m, type, listed);
}

int named_object_id(const mjModel* m, mjtObj type, const std::string& name) noexcept {
  return name.empty() ? -1 : mj_name2id(m, type, name.c_str());
}

int object_id(const mjModel* m, mjtObj type, const std::string& name) {
  (void)object_count(m, type);  // a type we look up
  const int found = named_object_id(m, type, name);
  if (found >= 0) return found;
  throw InvalidArgument(unknown_name_message(m, type, name));
}

bool is_index_text(std::string_view name) noexcept {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) { return c >= '0' && c <= '9'; });
}

int object_id_or_index(const mjModel* m, mjtObj type, const std::string& name, ObjectFilter listed) {
  const int id = named_object_id(m, type, name);
  if (id >= 0) return id;
  if (!is_index_text(name)) throw InvalidArgument(unknown_name_message(m, type, name, listed));
  // (More than 9 digits: past any count an int holds, so out of range.)
  if (name.size() <= 9 && std::stol(name) < object_count(m, type)) return static_cast<int>(std::stol(name));
  throw InvalidArgument(index_out_of_range_message(m, type, name, listed));
}

int checked_object_index(const mjModel* m, mjtObj type, long long index) {
  const int count = object_count(m, type);
  if (index >= 0 && index < count) return static_cast<int>(index);
  throw InvalidArgument(index_out_of_range_message(m, type, std::to_string(index)));
}

std::string did_you_mean(std::string_view name, const std::vector<std::string>& candidates) {
  // Edit distance with transpositions (optimal string alignment),
  // case-insensitive; a likely typo is at most a third of the longer name's
  // length away ("bodys" for "bodies"), and at least one edit for short names.
  const auto same = [](char a, char b) {
    return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
  };
  std::string best;
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  for (const std::string& candidate : candidates) {
    const std::size_t n = name.size(), k = candidate.size();
    if (std::max(n, k) - std::min(n, k) > std::max<std::size_t>(1, std::max(n, k) / 3)) continue;
    std::vector<std::vector<std::size_t>> dist(n + 1, std::vector<std::size_t>(k + 1));
    for (std::size_t i = 0; i <= n; ++i) dist[i][0] = i;
    for (std::size_t j = 0; j <= k; ++j) dist[0][j] = j;
    for (std::size_t i = 1; i <= n; ++i) {
      for (std::size_t j = 1; j <= k; ++j) {
        dist[i][j] = std::min({dist[i - 1][j] + 1, dist[i][j - 1] + 1,
                               dist[i - 1][j - 1] + (same(name[i - 1], candidate[j - 1]) ? 0 : 1)});
        if (i > 1 && j > 1 && same(name[i - 1], candidate[j - 2]) && same(name[i - 2], candidate[j - 1])) {
          dist[i][j] = std::min(dist[i][j], dist[i - 2][j - 2] + 1);
        }
      }
    }
    if (dist[n][k] <= std::max<std::size_t>(1, std::max(n, k) / 3) && dist[n][k] < best_distance) {
      best_distance = dist[n][k];
      best = candidate;
    }
  }
  return best;
}

}  // namespace simloop
