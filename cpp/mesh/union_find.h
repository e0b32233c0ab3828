// Disjoint sets with path halving and union by size, for components and fans.
#pragma once

#include <numeric>
#include <utility>
#include <vector>

namespace modal_deform {

class UnionFind {
 public:
  explicit UnionFind(int n) : parent_(n), size_(n, 1), count_(n) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }

  int find(int x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }

  // Joins the sets of a and b; returns the root of the joined set.
  int unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a == b) return a;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
    --count_;
    return a;
  }

  int count() const { return count_; }  // number of disjoint sets

 private:
  std::vector<int> parent_, size_;
  int count_;
};

}  // namespace modal_deform
