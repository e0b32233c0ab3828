// Race-free parallel assembly of per-vertex outputs (gradients, Hessian columns, third-derivative
// rows) from elements that share vertices.
//
// Part t owns the vertices [begin[t], begin[t + 1]) and visits, in element order, every element
// with a vertex it owns, writing only its own vertices' entries: no locks, no colouring, and each
// part sweeps its slice of the output in order. An element spanning parts is evaluated by each
// of them; meshes whose vertex order follows the surface (scans, most exports) have few such
// elements (docs/measurements.md, "Meshes as they come"). Every vertex sums its
// contributions in element order whatever the number of parts, so results do not depend on the
// number of threads.
#pragma once

#include <algorithm>
#include <vector>

namespace modal_deform {

struct VertexPartition {
  std::vector<int> begin;  // parts + 1 vertex indices, begin[0] = 0, begin[parts] = #V

  struct Range {
    int first, last;  // the vertices [first, last)
    bool contains(int vertex) const {
      return static_cast<unsigned>(vertex - first) < static_cast<unsigned>(last - first);
    }
  };

  int parts() const { return static_cast<int>(begin.size()) - 1; }
  Range range(int part) const { return {begin[part], begin[part + 1]}; }
};

// Splits the vertices 0 .. #work − 1 into `parts` contiguous ranges of about equal total work
// (work[v] ≥ 0, e.g. the number of element corners at v). parts ≥ 1.
inline VertexPartition balanced_partition(const std::vector<int>& work, int parts) {
  const int n = static_cast<int>(work.size());
  long long total = 0;
  for (int w : work) total += w;
  VertexPartition partition;
  partition.begin.assign(parts + 1, n);
  partition.begin[0] = 0;
  long long sum = 0;
  int part = 1;
  for (int v = 0; v < n && part < parts; ++v) {
    sum += work[v];
    while (part < parts && sum * parts >= total * part) partition.begin[part++] = v + 1;
  }
  return partition;
}

// For each part, the indices of the elements with a vertex it owns, ascending. Element: any type
// with a `vertices` array of vertex indices.
template <typename Element>
std::vector<std::vector<int>> elements_by_part(const VertexPartition& partition,
                                               const std::vector<Element>& elements) {
  std::vector<std::vector<int>> lists(partition.parts());
  for (int e = 0; e < static_cast<int>(elements.size()); ++e) {
    const auto& vertices = elements[e].vertices;
    for (int part = 0; part < partition.parts(); ++part) {
      const VertexPartition::Range range = partition.range(part);
      if (std::any_of(vertices.begin(), vertices.end(),
                      [range](int v) { return range.contains(v); }))
        lists[part].push_back(e);
    }
  }
  return lists;
}

}  // namespace modal_deform
