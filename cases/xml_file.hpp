#pragma once
// A G+Smo XML file held in memory with pugixml, and its one-line errors ("FILE: line N: what"):
// what the geometry reader (gismo_xml.cpp) and the problem reader (gismo_problem.cpp) share.
// Include only where pugixml is needed.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <pugixml.hpp>
#include <string>
#include <vector>

#include "basis/core/input_error.hpp"
#include "cases/geometry_file.hpp"

namespace knotwork {

// The most control points a file may hold (and twice that many numbers in one element).
inline constexpr long kMaxControlPoints = long(1) << 24;

class XmlFile {
 public:
  explicit XmlFile(const std::string& path) : path_(path), text_(read_geometry_text(path)) {
    const pugi::xml_parse_result r = doc_.load_buffer(text_.data(), text_.size());
    if (!r) throw InputError(at(r.offset) + ": malformed XML (" + r.description() + ")");
  }
  const pugi::xml_document& doc() const { return doc_; }
  std::string at(std::ptrdiff_t offset) const {
    long line = 1;
    for (std::ptrdiff_t i = 0; i < offset && i < static_cast<std::ptrdiff_t>(text_.size()); ++i) line += text_[i] == '\n';
    return path_ + ": line " + std::to_string(line);
  }
  std::string at(const pugi::xml_node& n) const { return at(n.offset_debug()); }
  [[noreturn]] void fail(const pugi::xml_node& n, const std::string& what) const { throw InputError(at(n) + ": " + what); }

  std::vector<double> numbers(const pugi::xml_node& n, const std::string& what) const {
    std::vector<double> out;
    const char* s = n.child_value();
    while (true) {
      while (*s && std::isspace(static_cast<unsigned char>(*s))) ++s;
      if (!*s) break;
      char* end = nullptr;
      const double v = std::strtod(s, &end);
      if (end == s || !std::isfinite(v) || (*end && !std::isspace(static_cast<unsigned char>(*end))))
        fail(n, what + ": '" + std::string(s, std::min<size_t>(std::strcspn(s, " \t\r\n"), 24)) + "' is not a finite number");
      out.push_back(v);
      s = end;
      if (out.size() > static_cast<size_t>(2 * kMaxControlPoints)) fail(n, what + ": too many numbers");
    }
    return out;
  }
  std::vector<long> integers(const pugi::xml_node& n, const std::string& what) const {
    std::vector<long> out;
    for (double v : numbers(n, what)) {
      if (v != std::floor(v) || std::abs(v) > 1e9) fail(n, what + ": " + std::to_string(v) + " is not an integer");
      out.push_back(static_cast<long>(v));
    }
    return out;
  }
  long integer_attribute(const pugi::xml_node& n, const char* name, const std::string& what) const {
    const pugi::xml_attribute a = n.attribute(name);
    if (!a) fail(n, what + ": the attribute " + name + " is missing");
    char* end = nullptr;
    const long v = std::strtol(a.value(), &end, 10);
    if (end == a.value() || *end) fail(n, what + ": " + name + "=\"" + a.value() + "\" is not an integer");
    return v;
  }

 private:
  std::string path_, text_;
  pugi::xml_document doc_;
};

}  // namespace knotwork
