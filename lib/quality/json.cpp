// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/quality/json.h"

#include <cmath>
#include <cstdio>

namespace nurbsfront::json {

std::string number(double x) {
  if (!std::isfinite(x)) return "null";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.10g", x);
  return buffer;
}

std::string string(std::string_view text) {
  std::string s = "\"";
  for (const char c : text) {
    switch (c) {
      case '"': s += "\\\""; break;
      case '\\': s += "\\\\"; break;
      case '\n': s += "\\n"; break;
      case '\r': s += "\\r"; break;
      case '\t': s += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof buffer, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
          s += buffer;
        } else {
          s += c;
        }
    }
  }
  return s + '"';
}

std::string array(const std::vector<std::string>& raw_values) {
  std::string s = "[";
  for (std::size_t i = 0; i < raw_values.size(); ++i) s += (i ? ", " : "") + raw_values[i];
  return s + "]";
}

Object& Object::add(const char* key, const std::string& raw) {
  out_ << (first_ ? "" : ", ") << '"' << key << "\": " << raw;
  first_ = false;
  return *this;
}

std::string Object::str() const {
  std::string s(1, '{');
  s += out_.str();
  s += '}';
  return s;
}

}  // namespace nurbsfront::json
