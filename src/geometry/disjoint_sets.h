#pragma once
// Union-find over the integers 0..n-1 (path halving): connected pieces of a mesh, fans around a vertex.
#include <numeric>
#include <vector>

namespace u3d {

struct DisjointSets {
  std::vector<int> parent;

  explicit DisjointSets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  // a's set joins b's: b's root stays the root.
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

}  // namespace u3d
