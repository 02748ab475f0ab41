// Scenario files' TOML tables, read with errors that name the file, the key
// and what is wrong: what scenario_toml.cc and scenario_reset_toml.cc share.
#pragma once

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "simloop/errors.hpp"
#include "simloop/number_format.hpp"
#include "simloop/object_names.hpp"
#include "simloop/scenario.hpp"

namespace simloop::detail {

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

// A scenario file's [reset] table (`table`, read by `t`); names and sizes
// are checked against the scene later (check_reset).
[[nodiscard]] ResetSpec read_reset(const TableReader& t, const toml::table& table, std::string_view source);

}  // namespace simloop::detail
