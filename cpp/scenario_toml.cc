// Scenario files' TOML: Scenario::from_toml_string (from_toml_file, in
// scenario.cc, reads a file into it), with errors that name the file, the key
// and what is wrong.
#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <string>
#include <tuple>
#include <utility>

#include "csv_schedule.hpp"
#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"
#include "simloop/scenario.hpp"
#include "simloop/scene_params.hpp"
#include "text_input.hpp"

namespace simloop {
namespace {

// --- TOML reading: every error names the source, the key and what is wrong.

class TableReader {
 public:
  TableReader(const toml::table& table, std::string source, std::string where = "")
      : table_(table), source_(std::move(source)), where_(std::move(where)) {}

  // "file.toml: control[0].key": where a value came from, for messages.
  [[nodiscard]] std::string where_text(std::string_view key) const {
    return source_ + ": " + (where_.empty() ? std::string(key) : where_ + "." + std::string(key));
  }

  // "file.toml: key: what", "file.toml: control[0].key: what".
  [[noreturn]] void fail(std::string_view key, const std::string& what) const {
    const std::string at = where_.empty() ? std::string(key) : key.empty() ? where_ : where_ + "." + std::string(key);
    throw InvalidArgument(source_ + ": " + (at.empty() ? "" : at + ": ") + what);
  }

  // Refuses keys this table does not know, naming the ones it does.
  void allow_only(std::initializer_list<std::string_view> keys) const {
    for (const auto& [key, value] : table_) {
      if (std::find(keys.begin(), keys.end(), key.str()) != keys.end()) continue;
      std::vector<std::string> known(keys.begin(), keys.end());
      std::string hint = did_you_mean(key.str(), known);
      std::string list;
      for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
      fail(key.str(),
           "unknown key" + (hint.empty() ? "" : " (did you mean '" + hint + "'?)") + "; known keys: " + list);
    }
  }

  [[nodiscard]] bool has(std::string_view key) const { return table_.contains(key); }
  [[nodiscard]] bool is_integer(std::string_view key) const {
    const toml::node* node = table_.get(key);
    return node != nullptr && node->is_integer();
  }

  [[nodiscard]] std::optional<double> number(std::string_view key) const {
    const toml::node* node = table_.get(key);
    if (node == nullptr) return std::nullopt;
    return as_number(*node, key);
  }

  [[nodiscard]] double as_number(const toml::node& node, std::string_view key) const {
    double value = 0.0;
    if (const auto* i = node.as_integer()) {
      value = static_cast<double>(i->get());
    } else if (const auto* f = node.as_floating_point()) {
      value = f->get();
    } else {
      fail(key, "expected a number, got " + type_name(node));
    }
    if (!std::isfinite(value)) fail(key, "expected a finite number, got " + python_float_repr(value));
    return value;
  }

  [[nodiscard]] std::optional<std::int64_t> integer(std::string_view key, std::int64_t minimum) const {
    const toml::node* node = table_.get(key);
    if (node == nullptr) return std::nullopt;
    const auto* i = node->as_integer();
    if (i == nullptr) fail(key, "expected a whole number, got " + type_name(*node));
    if (i->get() < minimum)
      fail(key, "must be at least " + std::to_string(minimum) + ", got " + std::to_string(i->get()));
    return i->get();
  }

  [[nodiscard]] std::optional<std::string> string(std::string_view key) const {
    const toml::node* node = table_.get(key);
    if (node == nullptr) return std::nullopt;
    const auto* s = node->as_string();
    if (s == nullptr) fail(key, "expected a string, got " + type_name(*node));
    return s->get();
  }

  [[nodiscard]] std::optional<bool> boolean(std::string_view key) const {
    const toml::node* node = table_.get(key);
    if (node == nullptr) return std::nullopt;
    const auto* b = node->as_boolean();
    if (b == nullptr) fail(key, "expected true or false, got " + type_name(*node));
    return b->get();
  }

  [[nodiscard]] std::optional<std::vector<double>> numbers(std::string_view key, std::size_t count) const {
    const toml::node* node = table_.get(key);
    if (node == nullptr) return std::nullopt;
    const auto* array = node->as_array();
    if (array == nullptr || array->size() != count) {
      fail(key, "expected an array of " + std::to_string(count) + " numbers, got " + type_name(*node));
    }
    std::vector<double> out;
    for (const toml::node& item : *array) out.push_back(as_number(item, key));
    return out;
  }

  // An array of numbers of any length (empty when the key is absent).
  [[nodiscard]] std::vector<double> number_list(std::string_view key) const {
    const toml::node* node = table_.get(key);
    if (node == nullptr) return {};
    const auto* array = node->as_array();
    if (array == nullptr) fail(key, "expected an array of numbers, got " + type_name(*node));
    std::vector<double> out;
    for (const toml::node& item : *array) out.push_back(as_number(item, key));
    return out;
  }

  [[nodiscard]] std::vector<std::string> strings(std::string_view key, std::string_view or_else = {}) const {
    const toml::node* node = table_.get(key);
    if (node == nullptr) return {};
    const auto* array = node->as_array();
    if (array == nullptr)
      fail(key, "expected an array of names" + std::string(or_else.empty() ? "" : " ") + std::string(or_else) +
                    ", got " + type_name(*node));
    std::vector<std::string> out;
    for (const toml::node& item : *array) {
      if (const auto* s = item.as_string()) {
        out.push_back(s->get());
      } else {
        fail(key, "expected an array of names, found " + type_name(item));
      }
    }
    return out;
  }

  // [[a, b], ...]: pairs of names (record's data: [array, object]).
  [[nodiscard]] std::vector<std::pair<std::string, std::string>> name_pairs(std::string_view key,
                                                                            std::string_view what) const {
    const toml::node* node = table_.get(key);
    if (node == nullptr) return {};
    const auto* array = node->as_array();
    if (array == nullptr) fail(key, "expected an array of " + std::string(what) + ", got " + type_name(*node));
    std::vector<std::pair<std::string, std::string>> out;
    for (const toml::node& item : *array) {
      const auto* pair = item.as_array();
      const bool ok = pair && pair->size() == 2 && pair->get(0)->is_string() && pair->get(1)->is_string();
      if (!ok) fail(key, "expected an array of " + std::string(what) + ", found " + type_name(item));
      out.emplace_back(pair->get(0)->as_string()->get(), pair->get(1)->as_string()->get());
    }
    return out;
  }

  // [[t, value], ...] pairs, `t` in the unit the key implies.
  [[nodiscard]] std::vector<std::pair<double, double>> pairs(std::string_view key) const {
    const toml::node* node = table_.get(key);
    const auto* array = node ? node->as_array() : nullptr;
    if (array == nullptr || array->empty()) fail(key, "expected an array of [time, value] pairs");
    std::vector<std::pair<double, double>> out;
    for (const toml::node& item : *array) {
      const auto* pair = item.as_array();
      if (pair == nullptr || pair->size() != 2) fail(key, "expected [time, value] pairs, found " + type_name(item));
      out.emplace_back(as_number(*pair->get(0), key), as_number(*pair->get(1), key));
      if (out.size() > 1 && out.back().first <= out[out.size() - 2].first) {
        fail(key, "times must increase, got " + python_float_repr(out[out.size() - 2].first) + " then " +
                      python_float_repr(out.back().first));
      }
    }
    return out;
  }

 private:
  static std::string type_name(const toml::node& node) {
    switch (node.type()) {
      case toml::node_type::string:
        return "a string";
      case toml::node_type::integer:
        return "an integer";
      case toml::node_type::floating_point:
        return "a number";
      case toml::node_type::boolean:
        return "a boolean";
      case toml::node_type::array:
        return "an array of " + std::to_string(node.as_array()->size());
      case toml::node_type::table:
        return "a table";
      default:
        return "a date or time";
    }
  }
  const toml::table& table_;
  std::string source_;  // the file
  std::string where_;   // the table in it: "" (the top), "control[0]", "record"
};

// A point in the run from one of `seconds_key` (s), `steps_key` (steps) or
// `fraction_key` (of the run's length); at most one may be given.
std::optional<When> read_when(const TableReader& t, std::string_view seconds_key, std::string_view steps_key,
                              std::string_view fraction_key = {}) {
  int given = 0;
  std::optional<When> when;
  if (const auto s = t.number(seconds_key)) {
    if (*s < 0) t.fail(seconds_key, "must not be negative, got " + python_float_repr(*s));
    when = When::seconds(*s);
    ++given;
  }
  if (const auto n = t.integer(steps_key, 0)) {
    when = When::steps(*n);
    ++given;
  }
  if (!fraction_key.empty()) {
    if (const auto f = t.number(fraction_key)) {
      if (*f < 0 || *f > 1) t.fail(fraction_key, "must be between 0 and 1, got " + python_float_repr(*f));
      when = When::fraction(*f);
      ++given;
    }
  }
  if (given > 1) {
    t.fail("", "give only one of " + std::string(seconds_key) + ", " + std::string(steps_key) +
                   (fraction_key.empty() ? "" : ", " + std::string(fraction_key)));
  }
  return when;
}

ControlSpec read_control(const TableReader& t, const std::filesystem::path& base) {
  t.allow_only({"actuator", "value", "schedule", "schedule_steps", "csv", "column"});
  ControlSpec c;
  if (!t.has("actuator")) t.fail("actuator", "missing: name the actuator (or give its index)");
  if (t.is_integer("actuator")) {
    c.actuator = std::to_string(*t.integer("actuator", 0));
  } else {
    c.actuator = *t.string("actuator");
  }
  const int forms = t.has("value") + t.has("schedule") + t.has("schedule_steps") + t.has("csv");
  if (forms != 1) {
    t.fail("", "give exactly one of value, schedule ([seconds, value] pairs), schedule_steps, csv (a value per step)");
  }
  if (t.has("column") && !t.has("csv")) t.fail("column", "only with csv");
  if (const auto file = t.string("csv")) {
    const std::filesystem::path p(*file);
    c.csv = p.is_absolute() || base.empty() ? p : base / p;
    c.schedule = detail::read_csv_schedule(c.csv, t.string("column").value_or(""), t.where_text("csv"));
  }
  if (const auto v = t.number("value")) c.schedule.emplace_back(When::steps(0), *v);
  if (t.has("schedule")) {
    for (const auto& [s, v] : t.pairs("schedule")) {
      if (s < 0) t.fail("schedule", "times must not be negative, got " + python_float_repr(s));
      c.schedule.emplace_back(When::seconds(s), v);
    }
  }
  if (t.has("schedule_steps")) {
    for (const auto& [s, v] : t.pairs("schedule_steps")) {
      if (s < 0 || s != std::floor(s))
        t.fail("schedule_steps", "steps must be whole and not negative, got " + python_float_repr(s));
      // Past any run (2^62 steps) it never acts; the clamp keeps the cast defined.
      c.schedule.emplace_back(When::steps(static_cast<std::int64_t>(std::min(s, 0x1p62))), v);
    }
  }
  return c;
}

DisturbanceSpec read_disturbance(const TableReader& t) {
  t.allow_only({"body", "force", "torque", "newtons", "direction", "random_sign", "start", "start_step",
                "start_fraction", "duration", "steps"});
  DisturbanceSpec d;
  // A body by name, or by index (a scene may leave its bodies unnamed).
  const auto body =
      t.is_integer("body") ? std::optional<std::string>(std::to_string(*t.integer("body", 0))) : t.string("body");
  if (!body) t.fail("body", "missing: name the body to push (or give its index)");
  d.body = *body;
  if (const auto f = t.numbers("force", 3)) std::copy(f->begin(), f->end(), d.force.begin());
  if (const auto q = t.numbers("torque", 3)) std::copy(q->begin(), q->end(), d.torque.begin());
  if (const auto n = t.numbers("newtons", 2)) {
    if ((*n)[0] < 0 || (*n)[1] < (*n)[0]) {
      t.fail("newtons", "expected [low, high] with 0 <= low <= high, got [" + python_float_repr((*n)[0]) + ", " +
                            python_float_repr((*n)[1]) + "]");
    }
    if (t.has("force")) t.fail("", "give force (fixed) or newtons with direction (drawn), not both");
    const auto dir = t.numbers("direction", 3);
    if (!dir) t.fail("direction", "missing: newtons draws a strength; direction says which way (a vector)");
    const double norm = std::sqrt((*dir)[0] * (*dir)[0] + (*dir)[1] * (*dir)[1] + (*dir)[2] * (*dir)[2]);
    if (norm == 0.0) t.fail("direction", "must not be zero");
    for (int i = 0; i < 3; ++i) d.force[static_cast<size_t>(i)] = (*dir)[static_cast<size_t>(i)] / norm;
    d.newtons = std::array<double, 2>{(*n)[0], (*n)[1]};
  } else if (t.has("direction")) {
    t.fail("direction", "only with newtons (a drawn strength)");
  }
  d.random_sign = t.boolean("random_sign").value_or(false);
  if (d.random_sign && !d.newtons) t.fail("random_sign", "only with newtons (a drawn strength)");
  if (const auto start = read_when(t, "start", "start_step", "start_fraction")) d.start = *start;
  if (const auto duration = read_when(t, "duration", "steps")) {
    const char* key = duration->unit == When::Unit::kSteps ? "steps" : "duration";
    if (duration->value == 0.0) t.fail(key, "must be positive (leave it out for one step, a kick)");
    d.duration = *duration;
  }
  return d;
}

// [reset]: how each run starts. Sizes and names are checked against the
// scene when the scenario is resolved (check_reset).
ResetSpec read_reset(const TableReader& t, const toml::table& table, std::string_view source) {
  t.allow_only({"qpos", "qvel", "qpos_noise", "qvel_noise", "param"});
  ResetSpec r;
  r.qpos = t.number_list("qpos");
  r.qvel = t.number_list("qvel");
  for (const auto& [key, noise] : {std::pair{"qpos_noise", &r.qpos_noise}, std::pair{"qvel_noise", &r.qvel_noise}}) {
    *noise = t.number(key).value_or(0.0);
    if (*noise < 0.0)
      t.fail(key, "must not be negative (the half-width of a uniform noise), got " + python_float_repr(*noise));
    if (!std::isfinite(2.0 * *noise))
      t.fail(key, "is too large: [-x, x] must be a range a double holds, got " + python_float_repr(*noise));
  }
  if (const toml::node* node = table.get("param")) {
    const auto* array = node->as_array();
    if (array == nullptr || (!array->empty() && !array->is_array_of_tables())) {
      t.fail("param", "expected [[reset.param]] tables (or param = [] for none)");
    }
    for (std::size_t i = 0; i < array->size(); ++i) {
      const TableReader p(*array->get(i)->as_table(), std::string(source), "reset.param[" + std::to_string(i) + "]");
      p.allow_only({"kind", "name", "value", "uniform"});
      const std::optional<std::string> kind = p.string("kind");
      if (!kind) p.fail("kind", "missing: friction, mass, damping or gravity");
      ResetSpec::Param param;
      try {
        param.kind = scene_param_kind(*kind);
      } catch (const InvalidArgument& e) {
        p.fail("kind", e.what());
      }
      param.name = p.string("name").value_or("");
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
    }
  }
  return r;
}

}  // namespace

Scenario Scenario::from_toml_string(std::string_view text, std::string_view source, const std::filesystem::path& base,
                                    std::string_view default_name) {
  detail::check_toml_key_parts(text, source);
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    const auto& at = e.source().begin;
    throw InvalidArgument(std::string(source) + ":" + std::to_string(at.line) + ":" + std::to_string(at.column) + ": " +
                          std::string(e.description()));
  }
  const TableReader top(root, std::string(source));
  top.allow_only({"name", "scene", "timestep", "steps", "duration", "control", "disturbance", "record", "reset"});
  Scenario s;
  s.name = top.string("name").value_or("");
  if (s.name.empty()) s.name = default_name;
  if (const auto scene = top.string("scene")) {
    if (scene->empty()) top.fail("scene", "must name an MJCF file (leave it out for the chapter's scene)");
    const std::filesystem::path p(*scene);
    s.scene = p.is_absolute() || base.empty() ? p : base / p;
  } else {
    s.timestep = Scenario::chapter().timestep;  // the chapter's scene runs at the chapter's timestep
  }
  if (const auto dt = top.number("timestep")) {
    if (*dt <= 0) top.fail("timestep", "must be a positive number of seconds, got " + python_float_repr(*dt));
    s.timestep = *dt;
  }
  if (const auto length = read_when(top, "duration", "steps")) {
    if (length->value <= 0) top.fail(length->unit == When::Unit::kSteps ? "steps" : "duration", "must be positive");
    s.length = *length;
  }
  const auto each_table = [&](std::string_view key, auto&& read) {
    const toml::node* node = root.get(key);
    if (node == nullptr) return;
    const auto* array = node->as_array();
    if (array == nullptr || !array->is_array_of_tables()) {
      top.fail(key, "expected [[" + std::string(key) + "]] tables");
    }
    for (std::size_t i = 0; i < array->size(); ++i) {
      read(TableReader(*array->get(i)->as_table(), std::string(source),
                       std::string(key) + "[" + std::to_string(i) + "]"));
    }
  };
  each_table("control", [&](const TableReader& t) { s.controls.push_back(read_control(t, base)); });
  each_table("disturbance", [&](const TableReader& t) { s.disturbances.push_back(read_disturbance(t)); });
  if (const toml::node* node = root.get("record")) {
    const auto* table = node->as_table();
    if (table == nullptr) top.fail("record", "expected a [record] table");
    const TableReader r(*table, std::string(source), "record");
    r.allow_only({"bodies", "joints", "actuators", "sensors", "tendons", "data", "contact_forces", "contacts", "ncon"});
    for (const auto& [key, names, all] : {std::tuple{"bodies", &s.record.bodies, &s.record.all_bodies},
                                          std::tuple{"joints", &s.record.joints, &s.record.all_joints},
                                          std::tuple{"actuators", &s.record.actuators, &s.record.all_actuators},
                                          std::tuple{"sensors", &s.record.sensors, &s.record.all_sensors},
                                          std::tuple{"tendons", &s.record.tendons, &s.record.all_tendons}}) {
      const toml::node* given = table->get(key);
      *all = given != nullptr && given->value<std::string>() == "all";
      if (!*all) *names = r.strings(key, "or \"all\"");
    }
    s.record.data = r.name_pairs("data", "[array, object] pairs (\"cfrc_ext\", \"torso\")");
    s.record.contact_forces = r.name_pairs("contact_forces", "[body or geom, body or geom] pairs");
    s.record.contacts = r.boolean("contacts").value_or(true);
    s.record.ncon = r.boolean("ncon").value_or(false);
  }
  if (const toml::node* node = root.get("reset")) {
    const auto* table = node->as_table();
    if (table == nullptr) top.fail("reset", "expected a [reset] table");
    s.reset = read_reset(TableReader(*table, std::string(source), "reset"), *table, source);
  }
  return s;
}

ResetSpec reset_over(const ResetSpec& own, std::string_view text, std::string_view source) {
  const ResetSpec given = Scenario::from_toml_string(text, source).reset;  // (checks the text)
  const toml::table root = toml::parse(text, source);
  ResetSpec r = own;
  const toml::table* table = root.get_as<toml::table>("reset");
  if (table == nullptr) return r;
  if (table->contains("qpos")) r.qpos = given.qpos;
  if (table->contains("qvel")) r.qvel = given.qvel;
  if (table->contains("qpos_noise")) r.qpos_noise = given.qpos_noise;
  if (table->contains("qvel_noise")) r.qvel_noise = given.qvel_noise;
  if (table->contains("param")) r.params = given.params;
  return r;
}

}  // namespace simloop
