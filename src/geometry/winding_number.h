#pragma once
// Generalized winding number (Jacobson et al. 2013): the signed solid angle of the surface seen from a
// point, over 4 pi. 1 inside and 0 outside a closed outward-oriented mesh; for meshes with holes,
// cracks or duplicated parts it degrades gracefully (about 0.5 across a hole), which makes
// "|w| >= 0.5" a robust inside test for imperfect reconstructions.
//
// Evaluated hierarchically (after Barill et al. 2018, lowest order): a far cluster of triangles is
// replaced by its total oriented area placed at its area-weighted centre (a dipole); near clusters
// are summed exactly. (The first-moment correction was tried and does not help on curved patches:
// it is of the same size as the neglected second-order term.)
#include <vector>

#include "geometry/triangle_bvh.h"

namespace u3d {

class WindingNumber {
 public:
  // `accuracy` (beta): a cluster is approximated when the query is farther than beta times the
  // cluster radius from its centre. The error falls like 1/beta^2; at 2 it stays below about 0.04
  // (measured on spheres), which cannot flip the 0.5 inside decision except within a hair of the
  // surface, where the nearby triangles are summed exactly anyway. 3 costs 4x the time for 0.01.
  explicit WindingNumber(const TriangleBvh& bvh, float accuracy = 2.f);

  double operator()(const Vec3f& query) const;

 private:
  struct Cluster {
    Eigen::Vector3d center;       // area-weighted centroid
    Eigen::Vector3d area_normal;  // sum of triangle area vectors (normal * area)
    double area = 0;              // total triangle area (weights the parent's centroid)
    double radius = 0;            // bounds every triangle vertex of the cluster
  };
  const TriangleBvh& bvh_;
  double accuracy_;
  std::vector<Cluster> clusters_;  // parallel to bvh_.nodes()
};

// Exact winding number by summing every triangle's solid angle: O(faces) per query, for tests.
double winding_number_exact(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                            const Vec3f& query);

}  // namespace u3d
