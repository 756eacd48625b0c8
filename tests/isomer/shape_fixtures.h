#pragma once
// Synthetic reconstruction targets: a known mesh, its four normal maps rendered by the same renderer,
// and the Chamfer distance between meshes.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "geometry/icosphere.h"
#include "isomer/normal_renderer.h"

namespace u3d::test {

// A smooth, not-too-simple closed shape: an ellipsoid with a bulge on its front-right side.
inline Mesh bulged_ellipsoid() {
  Mesh m = make_icosphere(4, 1.f);
  for (Vec3f& p : m.positions) {
    const Vec3f d = p;
    const float bump = 0.25f * std::exp(-((d - Vec3f(0.6f, 0.3f, 0.75f)).squaredNorm()) / 0.15f);
    p = Vec3f(0.7f * d.x(), 0.55f * d.y(), 0.4f * d.z()) * (1.f + bump);
  }
  return m;
}

inline std::vector<Camera> four_view_cameras(int resolution) {
  std::vector<Camera> c;
  for (View v : kAllViews) c.push_back(view_camera(v, resolution));
  return c;
}

// World-space normal maps RGBA (alpha = coverage, anti-aliased) of a mesh from the given cameras.
inline std::vector<Image> render_normal_maps(const Mesh& mesh, const std::vector<Camera>& cameras) {
  NormalRenderer r(cameras);
  const VertexNormals n = compute_vertex_normals(mesh.positions, mesh.faces);
  r.render(mesh.positions, mesh.faces, build_edge_topology(mesh.faces, mesh.positions.size()), n.unit);
  std::vector<Image> maps;
  for (size_t i = 0; i < cameras.size(); ++i) {
    Image img = r.view(i).image;
    // Stored un-premultiplied, as normal maps are: colour over partial alpha is divided back.
    for (size_t p = 0; p < img.pixel_count(); ++p) {
      float* px = img.data.data() + p * 4;
      if (px[3] > 0.f)
        for (int c = 0; c < 3; ++c) px[c] = std::min(1.f, px[c] / px[3]);
    }
    maps.push_back(std::move(img));
  }
  return maps;
}

// Points on a mesh: vertices plus face centroids.
inline std::vector<Vec3f> surface_points(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces) {
  std::vector<Vec3f> pts = positions;
  for (const Vec3i& f : faces) pts.push_back((positions[f[0]] + positions[f[1]] + positions[f[2]]) / 3.f);
  return pts;
}

// Symmetric mean nearest-point distance between two point sets.
inline double chamfer_distance(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  auto one_way = [](const std::vector<Vec3f>& from, const std::vector<Vec3f>& to) {
    double sum = 0;
    for (const Vec3f& p : from) {
      float best = std::numeric_limits<float>::max();
      for (const Vec3f& q : to) best = std::min(best, (p - q).squaredNorm());
      sum += std::sqrt(best);
    }
    return sum / double(from.size());
  };
  return 0.5 * (one_way(a, b) + one_way(b, a));
}

}  // namespace u3d::test

namespace u3d::test {

// Mean angle (degrees) between the rendered normals of a mesh and reference normal maps, over the
// pixels both cover confidently.
inline double mean_normal_error_deg(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                                    const std::vector<Image>& maps, const std::vector<Camera>& cameras) {
  NormalRenderer r(cameras);
  const VertexNormals n = compute_vertex_normals(positions, faces);
  r.render(positions, faces, build_edge_topology(faces, positions.size()), n.unit);
  double sum = 0;
  size_t count = 0;
  for (size_t i = 0; i < cameras.size(); ++i) {
    const DifferentiableView& v = r.view(i);
    for (int32_t p : v.covered) {
      const float* a = v.image.data.data() + size_t(p) * 4;
      const float* b = maps[i].data.data() + size_t(p) * 4;
      if (a[3] < 0.99f || b[3] < 0.99f) continue;
      const Vec3f na = Vec3f(a[0], a[1], a[2]) * 2.f - Vec3f::Ones();
      const Vec3f nb = Vec3f(b[0], b[1], b[2]) * 2.f - Vec3f::Ones();
      sum += std::acos(std::clamp(double(na.normalized().dot(nb.normalized())), -1.0, 1.0)) * 180.0 / M_PI;
      ++count;
    }
  }
  return count ? sum / double(count) : 180.0;
}

// The ellipsoid of bulged_ellipsoid() without its bulge, as a level-3 icosphere: a plausible coarse
// mesh that misses detail the refinement has to recover.
inline Mesh plain_ellipsoid() {
  Mesh m = make_icosphere(3, 1.f);
  for (Vec3f& p : m.positions) p = Vec3f(0.7f * p.x(), 0.55f * p.y(), 0.4f * p.z());
  return m;
}

}  // namespace u3d::test
