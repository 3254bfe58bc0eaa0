#pragma once
#include <string>
#include <utility>
#include <vector>

namespace knotwork {

struct JsonMember;

// A parsed JSON document (RFC 8259). Numbers keep their source text, so that integers stay
// integers and callers can read them exactly.
struct JsonValue {
  enum class Kind { kNull, kBool, kNumber, kString, kArray, kObject };
  Kind kind = Kind::kNull;
  bool boolean = false;
  double number = 0;
  bool integral = false;  // a number written without fraction or exponent
  std::string text;       // a string's value, or a number's source text
  std::vector<JsonValue> items;                           // kArray
  std::vector<JsonMember> members;  // kObject, in file order (a struct, not a std::pair: a pair
                                   // of an incomplete type is refused by clang's libstdc++ checks)
};

struct JsonMember {
  std::string key;
  JsonValue value;
};

// Parses `text`; throws InputError "<path>:<line>:<column>: JSON syntax error: ..." on bad
// input (also duplicate keys, and nesting deeper than 200 levels).
JsonValue parse_json(const std::string& text, const std::string& path);

// Reads and parses a file; InputError names the file when it cannot be read.
JsonValue read_json_file(const std::string& path);

}  // namespace knotwork
