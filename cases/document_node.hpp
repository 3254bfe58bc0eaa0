#pragma once
// One tree for every input document: TOML (toml++) and JSON (nlohmann-json) files both
// parse into it, and every reader validates it, so a JSON case gets exactly the checks and
// messages of a TOML one. The accessors follow toml++'s names (value_exact, as_table, get).
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace knotwork {

class DocumentNode {
 public:
  enum class Kind { kTable, kArray, kString, kInteger, kFloat, kBool };
  using Member = std::pair<std::string, DocumentNode>;

  static DocumentNode table() { return DocumentNode(Kind::kTable); }
  static DocumentNode array() { return DocumentNode(Kind::kArray); }
  static DocumentNode string(std::string s) {
    DocumentNode n(Kind::kString);
    n.text_ = std::move(s);
    return n;
  }
  static DocumentNode integer(std::int64_t v) {
    DocumentNode n(Kind::kInteger);
    n.integer_ = v;
    return n;
  }
  static DocumentNode floating(double v) {
    DocumentNode n(Kind::kFloat);
    n.number_ = v;
    return n;
  }
  static DocumentNode boolean(bool v) {
    DocumentNode n(Kind::kBool);
    n.boolean_ = v;
    return n;
  }

  Kind kind() const { return kind_; }
  bool is_table() const { return kind_ == Kind::kTable; }
  bool is_array() const { return kind_ == Kind::kArray; }
  const DocumentNode* as_table() const { return is_table() ? this : nullptr; }
  const DocumentNode* as_array() const { return is_array() ? this : nullptr; }

  // The value when the node holds exactly that type: std::int64_t (integers only), double
  // (floats only), std::string, bool; nullopt otherwise.
  template <class T>
  std::optional<T> value_exact() const;

  // Tables: the member named `key` (null if absent), and the members in document order.
  const DocumentNode* get(const std::string& key) const {
    for (const auto& m : members_)
      if (m.first == key) return &m.second;
    return nullptr;
  }
  const std::vector<Member>& members() const { return members_; }
  std::vector<Member>::const_iterator begin() const { return members_.begin(); }
  std::vector<Member>::const_iterator end() const { return members_.end(); }
  // Arrays: the i-th item (null past the end).
  const DocumentNode* get(std::size_t i) const { return i < items_.size() ? &items_[i] : nullptr; }
  std::size_t size() const { return is_table() ? members_.size() : items_.size(); }
  bool empty() const { return size() == 0; }

  // Building: appends to an array, or a member to a table (the parsers refuse duplicates).
  void push_back(DocumentNode n) { items_.push_back(std::move(n)); }
  void insert(std::string key, DocumentNode n) { members_.emplace_back(std::move(key), std::move(n)); }

 private:
  explicit DocumentNode(Kind k) : kind_(k) {}
  Kind kind_;
  std::string text_;
  std::int64_t integer_ = 0;
  double number_ = 0;
  bool boolean_ = false;
  std::vector<DocumentNode> items_;
  std::vector<Member> members_;
};

template <>
inline std::optional<std::int64_t> DocumentNode::value_exact<std::int64_t>() const {
  if (kind_ == Kind::kInteger) return integer_;
  return std::nullopt;
}
template <>
inline std::optional<double> DocumentNode::value_exact<double>() const {
  if (kind_ == Kind::kFloat) return number_;
  return std::nullopt;
}
template <>
inline std::optional<std::string> DocumentNode::value_exact<std::string>() const {
  if (kind_ == Kind::kString) return text_;
  return std::nullopt;
}
template <>
inline std::optional<bool> DocumentNode::value_exact<bool>() const {
  if (kind_ == Kind::kBool) return boolean_;
  return std::nullopt;
}

}  // namespace knotwork
