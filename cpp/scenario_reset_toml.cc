// A scenario file's [reset] table, and one episode's reset options over the
// scenario's own (reset_over).
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scene_params.hpp"
#include "toml_reader.hpp"

namespace simloop {

namespace detail {

namespace {

// A noise's width: a uniform noise's half-width or a normal one's standard deviation.
double noise_width(const TableReader& t, const std::string& key, const toml::node& node) {
  const double w = t.as_number(node, key);
  if (w < 0.0) {
    t.fail(key, "must not be negative (a uniform noise's half-width or a normal noise's standard deviation), got " +
                    python_float_repr(w));
  }
  if (!std::isfinite(2.0 * w)) {
    t.fail(key, "is too large: [-x, x] must be a range a double holds, got " + python_float_repr(w));
  }
  return w;
}

// qpos_noise or qvel_noise: a width, a width per coordinate, or widths by joint name.
ResetSpec::Noise read_noise(const TableReader& t, const toml::table& table, const std::string& key) {
  ResetSpec::Noise noise;
  if (const toml::node* node = table.get(key)) {
    if (const auto* array = node->as_array()) {
      for (const toml::node& item : *array) noise.each.push_back(noise_width(t, key, item));
    } else if (const auto* joints = node->as_table()) {
      for (const auto& [joint, width] : *joints) {
        noise.joints.emplace_back(std::string(joint.str()),
                                  noise_width(t, key + "." + std::string(joint.str()), width));
      }
    } else if (node->is_number()) {
      noise.scale = noise_width(t, key, *node);
    } else {
      t.fail(key, "expected a width, an array of widths (one per coordinate) or a table of widths by joint name");
    }
  }
  if (const auto distribution = t.string(key + "_distribution")) {
    if (*distribution == "normal") {
      noise.distribution = ResetSpec::Noise::Distribution::kNormal;
    } else if (*distribution != "uniform") {
      t.fail(key + "_distribution", "must be \"uniform\" or \"normal\", got \"" + *distribution + "\"");
    }
  }
  return noise;
}

// [[reset.goal]]: a mocap body's position, fixed (pos) or drawn (uniform = [low, high], corners of a box).
ResetSpec::Goal read_goal(const TableReader& g) {
  g.allow_only({"body", "pos", "uniform"});
  ResetSpec::Goal goal;
  const std::optional<std::string> body = g.string("body");
  if (!body) g.fail("body", "missing: name the mocap body to place");
  goal.body = *body;
  const auto pos = g.numbers("pos", 3);
  if (pos.has_value() == g.has("uniform")) {
    g.fail("", "give pos = [x, y, z] (fixed) or uniform = [[x, y, z], [x, y, z]] (drawn per run: low, high)");
  }
  if (pos) {
    std::copy(pos->begin(), pos->end(), goal.low.begin());
    goal.high = goal.low;
    return goal;
  }
  const std::vector<double> corners = g.rows_of_numbers("uniform", 2, 3);
  std::copy_n(corners.begin(), 3, goal.low.begin());
  std::copy_n(corners.begin() + 3, 3, goal.high.begin());
  for (std::size_t i = 0; i < 3; ++i) {
    if (!(goal.low[i] <= goal.high[i]) || !std::isfinite(goal.high[i] - goal.low[i])) {
      g.fail("uniform", "expected [low, high] corners with low <= high (each a range a double holds), got " +
                            python_float_repr(goal.low[i]) + " to " + python_float_repr(goal.high[i]));
    }
  }
  return goal;
}

// An array of tables ([[reset.param]], param = [] for none), each read by `read`.
template <class Read>
void each_table(const TableReader& t, const toml::table& table, std::string_view source, const std::string& key,
                Read&& read) {
  const toml::node* node = table.get(key);
  if (node == nullptr) return;
  const auto* array = node->as_array();
  if (array == nullptr || (!array->empty() && !array->is_array_of_tables())) {
    t.fail(key, "expected [[reset." + key + "]] tables (or " + key + " = [] for none)");
  }
  for (std::size_t i = 0; i < array->size(); ++i) {
    read(TableReader(*array->get(i)->as_table(), std::string(source), "reset." + key + "[" + std::to_string(i) + "]"));
  }
}

}  // namespace

// [reset]: how each run starts. Sizes and names are checked against the
// scene when the scenario is resolved (check_reset).
ResetSpec read_reset(const TableReader& t, const toml::table& table, std::string_view source) {
  t.allow_only({"qpos", "qvel", "qpos_noise", "qvel_noise", "qpos_noise_distribution", "qvel_noise_distribution",
                "keyframe", "goal", "param"});
  ResetSpec r;
  r.qpos = t.number_list("qpos");
  r.qvel = t.number_list("qvel");
  r.qpos_noise = read_noise(t, table, "qpos_noise");
  r.qvel_noise = read_noise(t, table, "qvel_noise");
  r.keyframe = t.string("keyframe").value_or("");  // "": the scene's reset pose
  each_table(t, table, source, "goal", [&](const TableReader& g) { r.goals.push_back(read_goal(g)); });
  each_table(t, table, source, "param", [&](const TableReader& p) {
    p.allow_only({"kind", "name", "value", "uniform", "field", "index"});
    const std::optional<std::string> kind = p.string("kind");
    if (!kind) p.fail("kind", "missing: friction, mass, damping, gravity or model");
    ResetSpec::Param param;
    try {
      param.kind = scene_param_kind(*kind);
    } catch (const InvalidArgument& e) {
      p.fail("kind", e.what());
    }
    param.name = p.string("name").value_or("");
    // A model value: which array, which value of the row (its object is `name`).
    const bool model = param.kind == SceneParam::Kind::kModel;
    for (const char* key : {"field", "index"}) {
      if (!model && p.has(key)) p.fail(key, "belongs to kind = \"model\" only");
    }
    param.field = p.string("field").value_or("");
    if (model && param.field.empty()) p.fail("field", "missing: a model value names an mjModel array (geom_friction)");
    const std::int64_t index = p.integer("index", 0).value_or(0);
    if (index > 1000) p.fail("index", "must be a value's place in a row (0 to the array's columns - 1)");
    param.index = static_cast<int>(index);
    const std::optional<double> value = p.number("value");
    const std::optional<std::vector<double>> range = p.numbers("uniform", 2);
    if (value.has_value() == range.has_value())
      p.fail("", "give value (fixed) or uniform = [low, high] (drawn per run)");
    if (range && !std::isfinite((*range)[1] - (*range)[0])) {
      p.fail("uniform", "is too wide: high - low must be a number a double holds");
    }
    if (range && (*range)[0] > (*range)[1]) {
      p.fail("uniform", "expected [low, high] with low <= high, got [" + python_float_repr((*range)[0]) + ", " +
                            python_float_repr((*range)[1]) + "]");
    }
    param.low = value ? *value : (*range)[0];
    param.high = value ? *value : (*range)[1];
    r.params.push_back(param);
  });
  return r;
}

}  // namespace detail

ResetSpec reset_over(const ResetSpec& own, std::string_view text, std::string_view source) {
  const ResetSpec given = Scenario::from_toml_string(text, source).reset;  // (checks the text)
  const toml::table root = toml::parse(text, source);
  ResetSpec r = own;
  const toml::table* table = root.get_as<toml::table>("reset");
  if (table == nullptr) return r;
  if (table->contains("qpos")) r.qpos = given.qpos;
  if (table->contains("qvel")) r.qvel = given.qvel;
  // A noise's widths and its distribution are keys of their own: each replaces only its own.
  for (const auto& [key, to, from] : {std::tuple{"qpos_noise", &r.qpos_noise, &given.qpos_noise},
                                      std::tuple{"qvel_noise", &r.qvel_noise, &given.qvel_noise}}) {
    if (table->contains(key)) {
      to->scale = from->scale;
      to->each = from->each;
      to->joints = from->joints;
    }
    if (table->contains(std::string(key) + "_distribution")) to->distribution = from->distribution;
  }
  if (table->contains("param")) r.params = given.params;
  if (table->contains("goal")) r.goals = given.goals;
  if (table->contains("keyframe")) r.keyframe = given.keyframe;
  return r;
}

}  // namespace simloop
