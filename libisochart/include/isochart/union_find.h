#pragma once
// Disjoint sets with path halving; the smaller index becomes the root, so the
// result does not depend on the order of unions.

#include <numeric>
#include <vector>

namespace isochart {

class UnionFind {
 public:
  explicit UnionFind(int n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  int find(int x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a < b) parent_[b] = a;
    else parent_[a] = b;
  }

 private:
  std::vector<int> parent_;
};

}  // namespace isochart
