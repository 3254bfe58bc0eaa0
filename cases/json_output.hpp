#pragma once
// JSON output of the commands (--json, convergence.json, exported bases), through
// nlohmann-json: this header stays light (nlohmann's is compiled in json_output.cpp only).
#include <memory>
#include <string>
#include <vector>

namespace knotwork {

// A JSON value built in order: members keep their insertion order; non-finite numbers
// become null; doubles that are integers print as integers (2, not 2.0).
class Json {
 public:
  static Json object();
  static Json array();
  static Json strings(const std::vector<std::string>& items);  // an array of strings
  Json(const Json& other);
  Json& operator=(const Json& other);
  ~Json();
  Json& set(const std::string& key, const Json& value);  // object member
  Json& set(const std::string& key, double value);
  Json& set(const std::string& key, long value);
  Json& set(const std::string& key, int value) { return set(key, static_cast<long>(value)); }
  Json& set(const std::string& key, const std::string& value);
  Json& set(const std::string& key, const char* value) { return set(key, std::string(value)); }
  Json& set_null(const std::string& key);
  Json& set_bool(const std::string& key, bool value);
  Json& push(const Json& value);  // array element
  Json& push(double value);
  Json& push(const std::string& value);
  // Indented by `indent` spaces; invalid UTF-8 in strings is replaced, never thrown on.
  std::string dump(int indent = 2) const;

 private:
  struct Impl;
  explicit Json(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// A number as CSV/JSON text (%.17g; "null" when not finite).
std::string json_number(double v);

}  // namespace knotwork
