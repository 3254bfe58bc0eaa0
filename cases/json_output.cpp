#include "cases/json_output.hpp"

#include <cmath>
#include <cstdio>

namespace knotwork {

std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string json_string(const std::string& s) {
  std::string r = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') { r += '\\'; r += static_cast<char>(c); }
    else if (c == '\n') r += "\\n";
    else if (c == '\t') r += "\\t";
    else if (c < 0x20) { char buf[8]; std::snprintf(buf, sizeof buf, "\\u%04x", c); r += buf; }
    else r += static_cast<char>(c);
  }
  return r + "\"";
}

Json Json::object() { return Json(); }
Json Json::array() { Json j; j.is_object_ = false; return j; }

Json Json::strings(const std::vector<std::string>& items) {
  Json j = array();
  for (const auto& s : items) j.push(s);
  return j;
}

Json& Json::set(const std::string& key, const Json& value) {
  child_of_item_.resize(items_.size(), -1);
  items_.emplace_back(key, "");
  children_.push_back(value);
  child_of_item_.push_back(static_cast<int>(children_.size()) - 1);
  return *this;
}
Json& Json::set(const std::string& key, double v) { items_.emplace_back(key, json_number(v)); return *this; }
Json& Json::set(const std::string& key, long v) { items_.emplace_back(key, std::to_string(v)); return *this; }
Json& Json::set(const std::string& key, const std::string& v) { items_.emplace_back(key, json_string(v)); return *this; }
Json& Json::set_null(const std::string& key) { items_.emplace_back(key, "null"); return *this; }
Json& Json::set_bool(const std::string& key, bool v) { items_.emplace_back(key, v ? "true" : "false"); return *this; }
Json& Json::push(const Json& value) { return set("", value); }
Json& Json::push(double v) { return set("", v); }
Json& Json::push(const std::string& v) { return set("", v); }

std::string Json::render(int indent, int level) const {
  const std::string pad(indent * (level + 1), ' '), end_pad(indent * level, ' ');
  const std::string nl = indent > 0 ? "\n" : "";
  std::string r = is_object_ ? "{" : "[";
  if (items_.empty()) return r + (is_object_ ? "}" : "]");
  r += nl;
  for (size_t i = 0; i < items_.size(); ++i) {
    r += pad;
    if (is_object_) r += json_string(items_[i].first) + (indent > 0 ? ": " : ":");
    const int child = i < child_of_item_.size() ? child_of_item_[i] : -1;
    r += child >= 0 ? children_[child].render(indent, level + 1) : items_[i].second;
    if (i + 1 < items_.size()) r += ",";
    r += nl;
  }
  return r + end_pad + (is_object_ ? "}" : "]");
}

std::string Json::dump(int indent) const { return render(indent, 0); }

}  // namespace knotwork
