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
#include "toml_reader.hpp"

namespace simloop {
namespace {

using detail::TableReader;

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
    r.allow_only({"bodies", "joints", "actuators", "sensors", "tendons", "data", "contacts", "ncon"});
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
    s.record.contacts = r.boolean("contacts").value_or(true);
    s.record.ncon = r.boolean("ncon").value_or(false);
  }
  if (const toml::node* node = root.get("reset")) {
    const auto* table = node->as_table();
    if (table == nullptr) top.fail("reset", "expected a [reset] table");
    s.reset = detail::read_reset(TableReader(*table, std::string(source), "reset"), *table, source);
  }
  return s;
}

}  // namespace simloop
