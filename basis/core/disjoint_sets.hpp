#pragma once
// Union-find over 0..n-1 (path halving): what gluing patches needs to make one function of
// several patches' copies. Written here: a dozen lines, where Boost's disjoint_sets would need
// its property-map plumbing.
#include <numeric>
#include <vector>

namespace knotwork {

class DisjointSets {
 public:
  explicit DisjointSets(int n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  int find(int i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  void unite(int a, int b) { parent_[find(a)] = find(b); }
  // One number per set, 0, 1, ... in the order of each set's first element.
  std::vector<int> numbering(int* count = nullptr) {
    std::vector<int> root_number(parent_.size(), -1), out(parent_.size());
    int n = 0;
    for (int i = 0; i < static_cast<int>(parent_.size()); ++i) {
      int& r = root_number[find(i)];
      if (r < 0) r = n++;
      out[i] = r;
    }
    if (count) *count = n;
    return out;
  }

 private:
  std::vector<int> parent_;
};

}  // namespace knotwork
