// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! The tiny JSON writer behind the reports' to_json() (flat objects built key by key; no
//! parsing). Shared by the quality and pipeline modules; not a general JSON library.

#include <cstddef>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace nurbsfront::json {

//! A number with 10 significant digits; "null" when not finite.
[[nodiscard]] std::string number(double x);
//! A quoted string with JSON escapes.
[[nodiscard]] std::string string(std::string_view text);
//! A JSON array of already-rendered values.
[[nodiscard]] std::string array(const std::vector<std::string>& raw_values);

//! A JSON object built by adding key/value pairs in order.
class Object {
 public:
  //! Adds a value that is already JSON (an object, array, number or null).
  Object& add(const char* key, const std::string& raw);
  Object& num(const char* key, double x) { return add(key, number(x)); }
  Object& count(const char* key, std::size_t n) { return add(key, std::to_string(n)); }
  Object& integer(const char* key, long n) { return add(key, std::to_string(n)); }
  Object& flag(const char* key, bool b) { return add(key, b ? "true" : "false"); }
  Object& text(const char* key, std::string_view s) { return add(key, string(s)); }
  //! The object, "{...}".
  [[nodiscard]] std::string str() const;

 private:
  std::ostringstream out_;
  bool first_ = true;
};

}  // namespace nurbsfront::json
