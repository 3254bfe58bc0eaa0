#pragma once
#include <stdexcept>
#include <string>

namespace knotwork {
// An error in what the user gave (a case file, a field, a command-line value). Its
// message is one line that names the file and the field and says what is wrong; the
// CLI prints it as it is and exits non-zero.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
}  // namespace knotwork

namespace knotwork {
// A geometry that cannot be used (e.g. a non-positive Jacobian); the CLI adds the case
// file and "[geometry]" to the message.
class GeometryError : public InputError {
 public:
  using InputError::InputError;
};
}  // namespace knotwork
