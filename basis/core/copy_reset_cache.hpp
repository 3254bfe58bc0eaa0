#pragma once
// A lazily built cache (an index over its owner's data) that a copy of the owner does not
// share: the copy starts empty and builds its own on first use, so it never points into the
// original. shared_ptr, not unique_ptr, so that T may stay incomplete in the owner's header.
#include <memory>

namespace knotwork {

template <class T>
struct CopyResetCache {
  std::shared_ptr<T> value;
  CopyResetCache() = default;
  CopyResetCache(const CopyResetCache&) {}
  CopyResetCache(CopyResetCache&&) noexcept = default;
  CopyResetCache& operator=(const CopyResetCache&) {
    value.reset();
    return *this;
  }
  CopyResetCache& operator=(CopyResetCache&&) noexcept = default;
};

}  // namespace knotwork
