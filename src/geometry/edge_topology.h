#pragma once
// Edge-based connectivity of a triangle mesh, rebuilt from the face list after each batch of edits:
// unique edges, the faces on both sides of each edge, the edge of each face side, and vertex rings.
// Edges are numbered by (lower, higher) vertex after a build; edits that patch the topology in place
// (flips) keep the numbers, so the order is not meaningful.
#include <array>
#include <vector>

#include "core/mesh.h"

namespace u3d {

struct EdgeTopology {
  static constexpr int kNone = -1;

  std::vector<std::array<int, 2>> edge_vertices;  // per edge, lower vertex index first
  // Per edge: the face traversing it lower -> higher ("left") and higher -> lower ("right"), each as
  // face * 3 + side (side i = from corner i to corner i + 1); kNone on a border.
  std::vector<std::array<int, 2>> edge_sides;
  std::vector<char> edge_manifold;  // 0 when more than two sides (or two in the same direction) share it
  std::vector<Vec3i> face_edges;    // per face: edge of side i
  std::vector<int> ring_offsets;    // CSR of vertex neighbours: ring of v = ring[ring_offsets[v] .. [v+1])
  std::vector<int> ring;            // each ring ascending after a build (not after patches)

  size_t edge_count() const { return edge_vertices.size(); }
  int degree(int v) const { return ring_offsets[v + 1] - ring_offsets[v]; }
  bool interior(int e) const { return edge_manifold[e] && edge_sides[e][0] >= 0 && edge_sides[e][1] >= 0; }
  bool border(int e) const { return edge_manifold[e] && (edge_sides[e][0] < 0 || edge_sides[e][1] < 0); }  // one face
  bool adjacent(int a, int b) const;
};

EdgeTopology build_edge_topology(const std::vector<Vec3i>& faces, size_t vertex_count);

// Recomputes the vertex rings from the edges (after edits that patched the edges).
void rebuild_rings(EdgeTopology& t, size_t vertex_count);

// Every face side of every edge, ascending, including those edge_sides has no slot for (a third face,
// or a second one traversing the edge the same way): the sides of edge e are sides[offsets[e] .. [e + 1]).
struct EdgeSideLists {
  std::vector<int> offsets;
  std::vector<int> sides;

  size_t edge_count() const { return offsets.size() - 1; }
  int count(int e) const { return offsets[e + 1] - offsets[e]; }
};
EdgeSideLists edge_side_lists(const EdgeTopology& t);

// The topology of a face list that is edited between uses: built on demand, dropped by edits that
// change the connectivity wholesale (collapses, splits), kept by edits that patch it (flips). Building
// is most of a remeshing pass's cost, and late in an optimisation many passes collapse or split nothing.
class TopologyCache {
 public:
  EdgeTopology& of(const std::vector<Vec3i>& faces, size_t vertex_count) {
    if (!valid_) topology_ = build_edge_topology(faces, vertex_count), valid_ = true;
    return topology_;
  }
  void invalidate() { valid_ = false; }

 private:
  EdgeTopology topology_;
  bool valid_ = false;
};

}  // namespace u3d
