#include "studies/report.hpp"

#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

namespace knotwork {

namespace {

void set_value(Json& j, const std::string& key, const ReportValue& v) {
  if (std::holds_alternative<std::monostate>(v)) j.set_null(key);
  else if (const double* d = std::get_if<double>(&v)) j.set(key, *d);
  else if (const long* l = std::get_if<long>(&v)) j.set(key, *l);
  else if (const std::string* s = std::get_if<std::string>(&v)) j.set(key, *s);
  else if (const bool* b = std::get_if<bool>(&v)) j.set_bool(key, *b);
  else j.set(key, Json::strings(std::get<std::vector<std::string>>(v)));
}

}  // namespace

std::vector<ReportField> condition_fields(const PoissonSolution& s) {
  std::vector<ReportField> out;
  std::string text, failure;
  for (const auto& [name, e] : {std::pair{"stiffness", &s.stiffness_spectrum}, std::pair{"mass", &s.mass_spectrum}}) {
    char line[160];
    if (e->computed)
      std::snprintf(line, sizeof line, "%s%s %.3e (eigenvalues %.3e to %.3e)", text.empty() ? "" : ", ", name,
                    e->condition(), e->smallest, e->largest);
    else {
      std::snprintf(line, sizeof line, "%s%s not estimated (%s)", text.empty() ? "" : ", ", name, e->failure.c_str());
      failure += (failure.empty() ? "" : "; ") + std::string(name) + ": " + e->failure;
    }
    text += line;
    out.push_back({.key = std::string("condition.") + name,
                   .value = e->computed ? ReportValue(e->condition()) : ReportValue{}, .column = true, .width = 20});
  }
  if (!failure.empty()) out.push_back({.key = "condition.failure", .value = failure});
  out.push_back({.key = "condition.scaling", .value = std::string("jacobi"),
                 .text = text + " [Jacobi-scaled, free dofs]", .label = "kappa"});
  return out;
}

void add_fields(Json& object, const std::vector<ReportField>& fields) {
  // Members of nested objects, in the order their first member appears.
  std::vector<std::string> order;
  std::map<std::string, Json> nested;
  for (const ReportField& f : fields) {
    const size_t dot = f.key.find('.');
    if (dot == std::string::npos) {
      set_value(object, f.key, f.value);
      continue;
    }
    const std::string outer = f.key.substr(0, dot);
    if (!nested.count(outer)) {
      order.push_back(outer);
      nested.emplace(outer, Json::object());
    }
    set_value(nested.at(outer), f.key.substr(dot + 1), f.value);
  }
  for (const auto& name : order) object.set(name, nested.at(name));
}

void print_field_lines(const std::vector<ReportField>& fields, int width) {
  for (const ReportField& f : fields)
    if (!f.text.empty()) std::printf("  %-*s %s\n", width, (f.label.empty() ? f.key : f.label).c_str(), f.text.c_str());
}

double field_number(const ReportField& f) {
  if (const double* d = std::get_if<double>(&f.value)) return *d;
  if (const long* l = std::get_if<long>(&f.value)) return static_cast<double>(*l);
  return NAN;
}

std::string field_csv(const ReportField& f) {
  if (const double* d = std::get_if<double>(&f.value)) return std::isfinite(*d) ? json_number(*d) : "";
  if (const long* l = std::get_if<long>(&f.value)) return std::to_string(*l);
  if (const std::string* s = std::get_if<std::string>(&f.value)) return *s;
  if (const bool* b = std::get_if<bool>(&f.value)) return *b ? "true" : "false";
  if (const auto* list = std::get_if<std::vector<std::string>>(&f.value)) {
    std::string r;
    for (const auto& s : *list) r += (r.empty() ? "" : ";") + s;
    return r;
  }
  return "";
}

const ReportField* find_field(const std::vector<ReportField>& fields, const std::string& key) {
  for (const auto& f : fields)
    if (f.key == key) return &f;
  return nullptr;
}

std::string rate_text(double rate) {
  if (std::isnan(rate)) return "-";
  char b[16];
  std::snprintf(b, sizeof b, "%.2f", rate);
  return b;
}

}  // namespace knotwork
