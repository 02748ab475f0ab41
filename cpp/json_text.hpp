// A JSON value written as Python's json.dumps(value, indent=2,
// sort_keys=True) writes it, for the metrics.json files (internal).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "simloop/number_format.hpp"

namespace simloop::detail {

// ensure_ascii as Python's default: non-ASCII as \uXXXX escapes.
struct Json {
  using Object = std::map<std::string, Json>;  // sorted keys, as sort_keys=True
  using Array = std::vector<Json>;
  std::variant<bool, std::int64_t, std::uint64_t, double, std::string, Array, Object> value;

  void dump(std::string& out, int indent) const {
    const std::string pad(static_cast<size_t>(indent + 2), ' '), close(static_cast<size_t>(indent), ' ');
    if (const auto* b = std::get_if<bool>(&value)) {
      out += *b ? "true" : "false";
    } else if (const auto* i = std::get_if<std::int64_t>(&value)) {
      out += std::to_string(*i);
    } else if (const auto* u = std::get_if<std::uint64_t>(&value)) {
      out += std::to_string(*u);
    } else if (const auto* x = std::get_if<double>(&value)) {
      out += std::isnan(*x) ? "NaN" : std::isinf(*x) ? (*x > 0 ? "Infinity" : "-Infinity") : python_float_repr(*x);
    } else if (const auto* s = std::get_if<std::string>(&value)) {
      quote(out, *s);
    } else if (const auto* a = std::get_if<Array>(&value)) {
      if (a->empty()) {
        out += "[]";
        return;
      }
      out += "[\n";
      for (size_t k = 0; k < a->size(); ++k) {
        out += pad;
        (*a)[k].dump(out, indent + 2);
        out += k + 1 < a->size() ? ",\n" : "\n";
      }
      out += close + "]";
    } else if (const auto* o = std::get_if<Object>(&value)) {
      if (o->empty()) {
        out += "{}";
        return;
      }
      out += "{\n";
      size_t k = 0;
      for (const auto& [key, item] : *o) {
        out += pad;
        quote(out, key);
        out += ": ";
        item.dump(out, indent + 2);
        out += ++k < o->size() ? ",\n" : "\n";
      }
      out += close + "}";
    }
  }

  static void quote(std::string& out, const std::string& text) {
    out += '"';
    for (size_t i = 0; i < text.size();) {
      const auto c = static_cast<unsigned char>(text[i]);
      char escaped[16];
      if (c == '"' || c == '\\') {
        out += '\\';
        out += static_cast<char>(c);
      } else if (c == '\n') {
        out += "\\n";
      } else if (c == '\r') {
        out += "\\r";
      } else if (c == '\t') {
        out += "\\t";
      } else if (c == '\b') {
        out += "\\b";
      } else if (c == '\f') {
        out += "\\f";
      } else if (c < 0x20 || c == 0x7f) {
        std::snprintf(escaped, sizeof escaped, "\\u%04x", c);
        out += escaped;
      } else if (c < 0x80) {
        out += static_cast<char>(c);
      } else {
        // UTF-8 to code point, then \uXXXX (a surrogate pair above U+FFFF).
        const int length = c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : c >= 0xc0 ? 2 : 1;
        std::uint32_t code = length == 1 ? 0xfffd : c & (0x7f >> length);
        for (int k = 1; k < length; ++k) {
          code = i + static_cast<size_t>(k) < text.size()
                     ? (code << 6) | (static_cast<unsigned char>(text[i + k]) & 0x3f)
                     : 0xfffd;
        }
        if (code > 0xffff) {
          code -= 0x10000;
          std::snprintf(escaped, sizeof escaped, "\\u%04x\\u%04x", 0xd800 + (code >> 10), 0xdc00 + (code & 0x3ff));
        } else {
          std::snprintf(escaped, sizeof escaped, "\\u%04x", code);
        }
        out += escaped;
        i += static_cast<size_t>(length);
        continue;
      }
      ++i;
    }
    out += '"';
  }
};

}  // namespace simloop::detail
