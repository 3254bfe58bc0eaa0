#pragma once
#include <string>
#include <vector>

namespace knotwork {

// A minimal JSON builder for the CLI's --json output: values are appended in order,
// non-finite numbers become null.
class Json {
 public:
  static Json object();
  static Json array();
  static Json strings(const std::vector<std::string>& items);  // an array of strings
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
  std::string dump(int indent = 2) const;

 private:
  bool is_object_ = true;
  std::vector<std::pair<std::string, std::string>> items_;  // key (empty for arrays), rendered value
  std::string render(int indent, int level) const;
  std::vector<Json> children_;
  std::vector<int> child_of_item_;
};

std::string json_number(double v);
std::string json_string(const std::string& s);

}  // namespace knotwork
