#include "geometry/winding_number.h"

#include <cmath>
#include <numbers>

namespace u3d {

namespace {

constexpr double kFourPi = 4.0 * std::numbers::pi;

// Signed solid angle of triangle (a, b, c) seen from q (Van Oosterom & Strackee 1983): positive when q
// lies behind the triangle's counter-clockwise side, i.e. inside for an outward-oriented mesh.
double solid_angle(const Vec3f& q, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  Eigen::Vector3d x = (a - q).cast<double>(), y = (b - q).cast<double>(), z = (c - q).cast<double>();
  double lx = x.norm(), ly = y.norm(), lz = z.norm();
  double numerator = x.dot(y.cross(z));
  double denominator = lx * ly * lz + x.dot(y) * lz + y.dot(z) * lx + z.dot(x) * ly;
  if (numerator == 0 && denominator == 0) return 0;  // q on the triangle itself: no defined angle
  return 2.0 * std::atan2(numerator, denominator);
}

}  // namespace

WindingNumber::WindingNumber(const TriangleBvh& bvh, float accuracy) : bvh_(bvh), accuracy_(accuracy) {
  const auto& nodes = bvh.nodes();
  const auto& tris = bvh.triangles();
  clusters_.resize(nodes.size());
  // Children come after their parent in depth-first order, so a reverse sweep sees children first.
  for (int n = int(nodes.size()) - 1; n >= 0; --n) {
    const auto& node = nodes[n];
    Cluster& c = clusters_[n];
    Eigen::Vector3d weighted_centroid = Eigen::Vector3d::Zero();
    c.area_normal.setZero();
    c.area = 0;
    if (node.leaf()) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        Eigen::Vector3d a = tris[i][0].cast<double>(), b = tris[i][1].cast<double>(), d = tris[i][2].cast<double>();
        Eigen::Vector3d area_vector = 0.5 * (b - a).cross(d - a);
        double area = area_vector.norm();
        c.area_normal += area_vector;
        weighted_centroid += area * (a + b + d) / 3.0;
        c.area += area;
      }
    } else {
      for (int child : {node.left, node.right}) {
        const Cluster& cc = clusters_[child];
        c.area_normal += cc.area_normal;
        weighted_centroid += cc.area * cc.center;
        c.area += cc.area;
      }
    }
    c.center = c.area > 0 ? Eigen::Vector3d(weighted_centroid / c.area) : node.box.center().cast<double>();
    // The farthest box corner bounds every vertex in the cluster.
    Eigen::Vector3d to_min = (node.box.min().cast<double>() - c.center).cwiseAbs();
    Eigen::Vector3d to_max = (node.box.max().cast<double>() - c.center).cwiseAbs();
    c.radius = to_min.cwiseMax(to_max).norm();
  }
}

double WindingNumber::operator()(const Vec3f& query) const {
  const auto& nodes = bvh_.nodes();
  const auto& tris = bvh_.triangles();
  const Eigen::Vector3d q = query.cast<double>();
  double total = 0;  // accumulated solid angle
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    int n = stack[--top];
    const auto& node = nodes[n];
    const Cluster& c = clusters_[n];
    Eigen::Vector3d r = c.center - q;
    double dist = r.norm();
    if (dist > accuracy_ * c.radius) {
      // Solid angle of a small oriented area element A seen along r: A.r / |r|^3.
      total += c.area_normal.dot(r) / (dist * dist * dist);
    } else if (node.leaf()) {
      for (int i = node.first; i < node.first + node.count; ++i)
        total += solid_angle(query, tris[i][0], tris[i][1], tris[i][2]);
    } else {
      stack[top++] = node.left;
      stack[top++] = node.right;
    }
  }
  return total / kFourPi;
}

double winding_number_exact(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                            const Vec3f& query) {
  double total = 0;
  for (const auto& f : faces) total += solid_angle(query, positions[f[0]], positions[f[1]], positions[f[2]]);
  return total / kFourPi;
}

}  // namespace u3d
