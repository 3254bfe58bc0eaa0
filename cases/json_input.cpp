// JSON input through nlohmann-json's SAX parser, into knotwork's own JsonValue (numbers keep
// their source text so callers can read decimals exactly). What nlohmann accepts and what
// it refuses is RFC 8259; knotwork adds its own refusals: duplicate keys, nesting deeper than
// 200 levels, numbers out of the double range.
#include "cases/json_input.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

using json = nlohmann::json;

// "<line>:<column>" of a byte offset in the text (1-based).
std::string line_and_column(const std::string& text, size_t offset) {
  size_t line = 1, column = 1;
  for (size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') line = 1 + line, column = 1;
    else ++column;
  }
  return std::to_string(line) + ":" + std::to_string(column);
}

class Builder final : public nlohmann::json_sax<json> {
 public:
  Builder(const std::string& text, const std::string& path) : text_(text), path_(path) {}

  JsonValue result() { return std::move(root_); }

  bool null() override { return put(JsonValue{}); }
  bool boolean(bool b) override {
    JsonValue v;
    v.kind = JsonValue::Kind::kBool;
    v.boolean = b;
    return put(std::move(v));
  }
  bool number_integer(number_integer_t i) override { return integer(std::to_string(i), static_cast<double>(i)); }
  bool number_unsigned(number_unsigned_t u) override { return integer(std::to_string(u), static_cast<double>(u)); }
  bool number_float(number_float_t d, const string_t& s) override {
    if (!std::isfinite(d)) return refuse("number out of range: " + s);
    JsonValue v;
    v.kind = JsonValue::Kind::kNumber;
    v.number = d;
    // An integer too large for 64 bits arrives here too; it is still written without fraction.
    v.integral = s.find_first_of(".eE") == std::string::npos;
    v.text = s;
    return put(std::move(v));
  }
  bool string(string_t& s) override {
    JsonValue v;
    v.kind = JsonValue::Kind::kString;
    v.text = std::move(s);
    return put(std::move(v));
  }
  bool binary(binary_t&) override { return refuse("binary values are not JSON text"); }
  bool start_object(std::size_t) override { return open(JsonValue::Kind::kObject); }
  bool key(string_t& k) override {
    if (!stack_.back().keys.insert(k).second) return refuse("duplicate key \"" + k + "\"" + where());
    stack_.back().pending_key = std::move(k);
    return true;
  }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(JsonValue::Kind::kArray); }
  bool end_array() override { return close(); }
  bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception& ex) override {
    // nlohmann's message: "[json.exception.parse_error.101] parse error at line L, column C: what".
    // Other errors: "[json.exception.out_of_range.406] what". The message keeps one line of
    // printable ASCII (the last bytes read may be invalid UTF-8).
    std::string what = ex.what();
    const size_t parse = what.find("parse error");
    const size_t colon = parse == std::string::npos ? std::string::npos : what.find(": ", parse);
    if (colon != std::string::npos) what = what.substr(colon + 2);
    else if (const size_t bracket = what.find("] "); what.rfind("[json.exception", 0) == 0 && bracket != std::string::npos)
      what = what.substr(bracket + 2);
    for (char& c : what)
      if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
    const size_t offset = position > 0 ? position - 1 : 0;
    throw InputError(path_ + ":" + line_and_column(text_, offset) + ": JSON syntax error: " + what);
  }

  // Set when a handler refused the document (nlohmann then stops without an error of its own).
  const std::string& refusal() const { return refusal_; }

 private:
  struct Open {
    JsonValue value;
    std::set<std::string> keys;
    std::string pending_key;
  };

  bool integer(std::string text, double value) {
    JsonValue v;
    v.kind = JsonValue::Kind::kNumber;
    v.number = value;
    v.integral = true;
    v.text = std::move(text);
    return put(std::move(v));
  }
  bool open(JsonValue::Kind kind) {
    if (stack_.size() >= 200) return refuse("nesting deeper than 200 levels");
    stack_.push_back({});
    stack_.back().value.kind = kind;
    return true;
  }
  bool close() {
    JsonValue v = std::move(stack_.back().value);
    stack_.pop_back();
    return put(std::move(v));
  }
  bool put(JsonValue v) {
    if (stack_.empty()) {
      root_ = std::move(v);
      return true;
    }
    Open& top = stack_.back();
    if (top.value.kind == JsonValue::Kind::kArray) top.value.items.push_back(std::move(v));
    else top.value.members.push_back({std::move(top.pending_key), std::move(v)});
    return true;
  }
  bool refuse(const std::string& why) {
    refusal_ = why;
    return false;
  }
  // " in <key path>" of the object being read, for messages without a position.
  std::string where() const {
    std::string path;
    for (size_t i = 0; i + 1 < stack_.size(); ++i)
      if (stack_[i].value.kind == JsonValue::Kind::kObject) {
        if (!path.empty()) path += '.';
        path += stack_[i].pending_key;
      } else {
        path += '[';
        path += std::to_string(stack_[i].value.items.size());
        path += ']';
      }
    // (appended piece by piece: GCC 12 warns, wrongly, about copies in "a" + b + "c")
    return path.empty() ? std::string(" in the top-level object") : std::string(" in ").append(path);
  }

  const std::string& text_;
  const std::string& path_;
  std::vector<Open> stack_;
  JsonValue root_;
  std::string refusal_;
};

}  // namespace

JsonValue parse_json(const std::string& text, const std::string& path) {
  Builder builder(text, path);
  const bool ok = json::sax_parse(text, &builder, json::input_format_t::json, true, false);
  if (!ok) throw InputError(path + ": JSON: " + (builder.refusal().empty() ? "not a JSON document" : builder.refusal()));
  return builder.result();
}

JsonValue read_json_file(const std::string& path) {
  if (std::filesystem::is_directory(path)) throw InputError(path + ": is a directory, not a JSON file");
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const std::string why = std::filesystem::exists(path) ? "cannot be read" : "no such file";
    throw InputError(path + ": cannot open (" + why + ")");
  }
  std::ostringstream s;
  s << in.rdbuf();
  return parse_json(s.str(), path);
}

}  // namespace knotwork
