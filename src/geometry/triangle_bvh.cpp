#include "geometry/triangle_bvh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/error.h"

namespace u3d {

namespace {

constexpr int kLeafSize = 4;

Vec3f closest_point_on_segment(const Vec3f& p, const Vec3f& a, const Vec3f& b) {
  Vec3f ab = b - a;
  float len2 = ab.squaredNorm();
  if (len2 <= 0) return a;
  float t = std::clamp((p - a).dot(ab) / len2, 0.f, 1.f);
  return a + t * ab;
}

}  // namespace

// Voronoi-region walk over vertices, edges and face (as in Ericson, Real-Time Collision Detection).
// Zero-area triangles make the face-region division meaningless, so they fall back to their edges.
Vec3f closest_point_on_triangle(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  Vec3f ab = b - a, ac = c - a;
  float scale = std::max(ab.squaredNorm(), ac.squaredNorm());
  if (ab.cross(ac).squaredNorm() <= 1e-12f * scale * scale) {
    Vec3f candidates[3] = {closest_point_on_segment(p, a, b), closest_point_on_segment(p, b, c),
                           closest_point_on_segment(p, c, a)};
    Vec3f best = candidates[0];
    for (const auto& q : candidates)
      if ((q - p).squaredNorm() < (best - p).squaredNorm()) best = q;
    return best;
  }
  Vec3f ap = p - a;
  float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  Vec3f bp = p - b;
  float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  Vec3f cp = p - c;
  float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  float denom = 1.f / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

TriangleBvh::TriangleBvh(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces) {
  require(!faces.empty(), "cannot build a triangle hierarchy of a mesh without faces");
  triangles_.resize(faces.size());
  face_index_.resize(faces.size());
  std::iota(face_index_.begin(), face_index_.end(), 0);
  std::vector<Vec3f> centroids(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) triangles_[f][k] = positions[faces[f][k]];
    centroids[f] = (triangles_[f][0] + triangles_[f][1] + triangles_[f][2]) / 3.f;
  }
  nodes_.reserve(2 * faces.size() / kLeafSize + 1);
  build(0, int(faces.size()), centroids);
  // build() partitioned face_index_; put the triangles in the same (leaf) order.
  std::vector<Triangle> ordered(triangles_.size());
  for (size_t i = 0; i < ordered.size(); ++i) ordered[i] = triangles_[face_index_[i]];
  triangles_.swap(ordered);
}

int TriangleBvh::build(int begin, int end, std::vector<Vec3f>& centroids) {
  int index = int(nodes_.size());
  nodes_.emplace_back();
  Eigen::AlignedBox3f box, centroid_box;
  for (int i = begin; i < end; ++i) {
    for (const auto& v : triangles_[face_index_[i]]) box.extend(v);
    centroid_box.extend(centroids[face_index_[i]]);
  }
  nodes_[index].box = box;
  if (end - begin <= kLeafSize) {
    nodes_[index].first = begin;
    nodes_[index].count = end - begin;
    return index;
  }
  int axis;
  centroid_box.sizes().maxCoeff(&axis);
  int mid = (begin + end) / 2;
  std::nth_element(face_index_.begin() + begin, face_index_.begin() + mid, face_index_.begin() + end,
                   [&](int a, int b) { return centroids[a][axis] < centroids[b][axis]; });
  int left = build(begin, mid, centroids);
  int right = build(mid, end, centroids);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

TriangleBvh::Closest TriangleBvh::closest_point(const Vec3f& query) const {
  Closest best;
  float best_d2 = std::numeric_limits<float>::infinity();
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (node.box.squaredExteriorDistance(query) >= best_d2) continue;
    if (node.leaf()) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const Triangle& t = triangles_[i];
        Vec3f q = closest_point_on_triangle(query, t[0], t[1], t[2]);
        float d2 = (q - query).squaredNorm();
        if (d2 < best_d2) {
          best_d2 = d2;
          best.point = q;
          best.face = face_index_[i];
        }
      }
      continue;
    }
    // Visit the nearer child first (pushed last) so the far one is usually pruned.
    float dl = nodes_[node.left].box.squaredExteriorDistance(query);
    float dr = nodes_[node.right].box.squaredExteriorDistance(query);
    if (dl < dr) {
      stack[top++] = node.right;
      stack[top++] = node.left;
    } else {
      stack[top++] = node.left;
      stack[top++] = node.right;
    }
  }
  best.distance = std::sqrt(best_d2);
  return best;
}

}  // namespace u3d
