#pragma once
// Bounding-volume hierarchy over the triangles of a mesh: exact closest-point queries in O(log n)
// (surface distances for Chamfer/F-score) and the tree on which the fast winding number is built.
#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "core/mesh.h"

namespace u3d {

class TriangleBvh {
 public:
  struct Node {
    Eigen::AlignedBox3f box;
    int first = 0;   // leaves: first triangle (in triangles() order); inner nodes: unused
    int count = 0;   // leaves: number of triangles (> 0); inner nodes: 0
    int left = -1;   // inner nodes: child indices
    int right = -1;
    bool leaf() const { return count > 0; }
  };
  using Triangle = std::array<Vec3f, 3>;

  // Copies the triangles (degenerate ones included: they are harmless to every query).
  // Throws Error when there are no faces.
  TriangleBvh(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces);

  struct Closest {
    float distance = 0;  // Euclidean distance to the surface
    int face = -1;       // index into the original face list
    Vec3f point{0, 0, 0};
  };
  Closest closest_point(const Vec3f& query) const;

  // Tree in depth-first order, root first.
  const std::vector<Node>& nodes() const { return nodes_; }
  // Triangles in leaf order; original_face(i) maps back to the caller's face index.
  const std::vector<Triangle>& triangles() const { return triangles_; }
  int original_face(int i) const { return face_index_[i]; }

 private:
  int build(int begin, int end, std::vector<Vec3f>& centroids);

  std::vector<Node> nodes_;
  std::vector<Triangle> triangles_;
  std::vector<int> face_index_;
};

// Closest point to p on the triangle (a, b, c); robust to zero-area triangles.
Vec3f closest_point_on_triangle(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c);

}  // namespace u3d
