#include "cases/json_output.hpp"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

namespace knotwork {

struct Json::Impl {
  nlohmann::ordered_json value;
};

namespace {

nlohmann::ordered_json number(double v) {
  if (!std::isfinite(v)) return nullptr;
  if (v == std::trunc(v) && std::abs(v) < 9007199254740992.0) return static_cast<long long>(v);
  return v;
}

}  // namespace

std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

Json::Json(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Json::Json(const Json& other) : impl_(std::make_unique<Impl>(*other.impl_)) {}
Json& Json::operator=(const Json& other) {
  if (this != &other) impl_ = std::make_unique<Impl>(*other.impl_);
  return *this;
}
Json::~Json() = default;

Json Json::object() { return Json(std::make_unique<Impl>(Impl{nlohmann::ordered_json::object()})); }
Json Json::array() { return Json(std::make_unique<Impl>(Impl{nlohmann::ordered_json::array()})); }

Json Json::strings(const std::vector<std::string>& items) {
  Json j = array();
  for (const auto& s : items) j.push(s);
  return j;
}

Json& Json::set(const std::string& key, const Json& v) { impl_->value[key] = v.impl_->value; return *this; }
Json& Json::set(const std::string& key, double v) { impl_->value[key] = number(v); return *this; }
Json& Json::set(const std::string& key, long v) { impl_->value[key] = v; return *this; }
Json& Json::set(const std::string& key, const std::string& v) { impl_->value[key] = v; return *this; }
Json& Json::set_null(const std::string& key) { impl_->value[key] = nullptr; return *this; }
Json& Json::set_bool(const std::string& key, bool v) { impl_->value[key] = v; return *this; }
Json& Json::push(const Json& v) { impl_->value.push_back(v.impl_->value); return *this; }
Json& Json::push(double v) { impl_->value.push_back(number(v)); return *this; }
Json& Json::push(const std::string& v) { impl_->value.push_back(v); return *this; }

std::string Json::dump(int indent) const {
  return impl_->value.dump(indent, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

}  // namespace knotwork
