#include "isomer/initial_mesh.h"

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/mesh_repair.h"
#include "geometry/open3d_bridge.h"

namespace u3d {
namespace {

// A view's world normals resampled to `res`, converted to its camera space, with the mask.
void camera_normals(const ViewSet& views, View v, int res, std::vector<Vec3f>& normals, std::vector<uint8_t>& mask) {
  const Image& src = views[v].normals;
  const Image img = src.width == res ? src : resize_image(src, res, res);
  const Eigen::Matrix3f world_to_camera = view_camera(v, res).rotation();
  normals.assign(img.pixel_count(), Vec3f(0, 0, 1));
  mask.assign(img.pixel_count(), 0);
  for (size_t i = 0; i < img.pixel_count(); ++i) {
    const float* px = &img.data[i * 4];
    const Vec3f n(px[0], px[1], px[2]);
    if (!is_foreground(px[3]) || n.norm() < 1e-3f) continue;
    mask[i] = 1;
    normals[i] = world_to_camera * n.normalized();
  }
}

// Pixels of the mask that touch the background (4-neighbourhood) or the image border.
bool on_rim(const std::vector<uint8_t>& mask, int res, int x, int y) {
  if (x == 0 || y == 0 || x == res - 1 || y == res - 1) return true;
  const size_t i = size_t(y) * res + x;
  return !mask[i - 1] || !mask[i + 1] || !mask[i - res] || !mask[i + res];
}

// World z range covered by a side view's mask: the right camera's image x runs along world -z, the
// left camera's along +z. Pixel edges, not centres, bound the object.
std::pair<float, float> side_depth_range(const ViewSet& views, View v) {
  const Image& n = views[v].normals;
  const int res = n.width;
  int lo = res, hi = -1;
  for (int y = 0; y < res; ++y)
    for (int x = 0; x < res; ++x)
      if (is_foreground(n.at(x, y, 3))) lo = std::min(lo, x), hi = std::max(hi, x);
  const float x_min = 2.f * lo / res - 1.f, x_max = 2.f * (hi + 1) / res - 1.f;
  return v == View::Right ? std::make_pair(-x_max, -x_min) : std::make_pair(x_min, x_max);
}

// One view's sheet in world space: a vertex per mask pixel, two triangles per fully covered 2x2 block,
// wound counter-clockwise as seen from the view's camera (so normals point toward it).
void add_sheet(View v, int res, const std::vector<float>& height, const std::vector<uint8_t>& mask, float depth_offset,
               float scale, open3d::geometry::TriangleMesh& out) {
  const Eigen::Matrix3d camera_to_world = view_camera(v, res).rotation().transpose().cast<double>();
  std::vector<int> index(size_t(res) * res, -1);
  for (int y = 0; y < res; ++y)
    for (int x = 0; x < res; ++x) {
      const size_t i = size_t(y) * res + x;
      if (!mask[i]) continue;
      index[i] = int(out.vertices_.size());
      const Eigen::Vector3d cam((x + 0.5) * 2.0 / res - 1.0, 1.0 - (y + 0.5) * 2.0 / res,
                                depth_offset + scale * height[i]);
      out.vertices_.push_back(camera_to_world * cam);
    }
  for (int y = 0; y + 1 < res; ++y)
    for (int x = 0; x + 1 < res; ++x) {
      const size_t i = size_t(y) * res + x;
      const int a = index[i], b = index[i + 1], c = index[i + res], d = index[i + res + 1];
      if (a >= 0 && b >= 0 && c >= 0) out.triangles_.push_back({a, c, b});
      if (d >= 0 && b >= 0 && c >= 0) out.triangles_.push_back({d, b, c});
    }
}

}  // namespace

DepthSheets integrate_front_and_back(const ViewSet& views, const InitialMeshOptions& options) {
  require(options.integration_resolution >= 16, "initial mesh: integration resolution must be at least 16");
  DepthSheets sheets;
  const int res = sheets.resolution = options.integration_resolution;
  const float pixel = 2.f / float(res);
  for (View v : {View::Front, View::Back}) {
    std::vector<Vec3f> normals;
    std::vector<uint8_t>& mask = v == View::Front ? sheets.front_mask : sheets.back_mask;
    camera_normals(views, v, res, normals, mask);
    require(std::count(mask.begin(), mask.end(), 1) > 0,
            std::string("initial mesh: the ") + view_name(v) + " mask vanishes at " + std::to_string(res) + " px");
    std::vector<float> h = integrate_normal_map(normals, mask, res, res, options.integration);
    const Eigen::Matrix3f camera_to_world = view_camera(v, res).rotation().transpose();
    for (Vec3f& n : normals) n = camera_to_world * n;
    (v == View::Front ? sheets.front_normals : sheets.back_normals) = normals;
    // The rim is where front and back meet: pin it to zero height (as the official code does).
    for (int y = 0; y < res; ++y)
      for (int x = 0; x < res; ++x) {
        const size_t i = size_t(y) * res + x;
        h[i] = (mask[i] && !on_rim(mask, res, x, y)) ? h[i] * pixel : 0.f;
      }
    (v == View::Front ? sheets.front_height : sheets.back_height) = std::move(h);
  }

  const auto [right_min, right_max] = side_depth_range(views, View::Right);
  const auto [left_min, left_max] = side_depth_range(views, View::Left);
  sheets.z_min = 0.5f * (right_min + left_min);
  sheets.z_max = 0.5f * (right_max + left_max);
  const float front_peak = std::max(0.f, *std::max_element(sheets.front_height.begin(), sheets.front_height.end()));
  const float back_peak = std::max(0.f, *std::max_element(sheets.back_height.begin(), sheets.back_height.end()));
  const float total = front_peak + back_peak;
  // Flat height maps (no relief) leave a slab between z_min and z_max.
  sheets.scale = total > 1e-6f ? (sheets.z_max - sheets.z_min) / total : 0.f;
  sheets.rim_z = total > 1e-6f ? sheets.z_max - sheets.scale * front_peak : 0.5f * (sheets.z_min + sheets.z_max);
  return sheets;
}

Mesh build_initial_mesh(const ViewSet& views, const InitialMeshOptions& options) {
  require(options.target_faces >= 100, "initial mesh: target face count must be at least 100");
  StageTimer t_integrate("initial mesh: integrating front and back normals");
  const DepthSheets sheets = integrate_front_and_back(views, options);
  t_integrate.finish();
  const bool slab = sheets.scale == 0.f;

  open3d::geometry::TriangleMesh joined;
  // Front camera z is world z; the back camera's z is world -z.
  add_sheet(View::Front, sheets.resolution, sheets.front_height, sheets.front_mask, slab ? sheets.z_max : sheets.rim_z,
            sheets.scale, joined);
  add_sheet(View::Back, sheets.resolution, sheets.back_height, sheets.back_mask, slab ? -sheets.z_min : -sheets.rim_z,
            sheets.scale, joined);
  // Point normals: the input normals. They agree with the sheets' own normals where the heights are
  // right (scale 1), and at the rim they point sideways, which lets Poisson reach the silhouette.
  for (const auto* list : {&sheets.front_normals, &sheets.back_normals})
    for (size_t i = 0; i < list->size(); ++i)
      if ((list == &sheets.front_normals ? sheets.front_mask : sheets.back_mask)[i])
        joined.vertex_normals_.push_back((*list)[i].cast<double>());

  open3d::geometry::PointCloud points;
  points.points_ = joined.vertices_;
  points.normals_ = joined.vertex_normals_;
  StageTimer t_poisson("initial mesh: Poisson on " + std::to_string(points.points_.size()) + " points");
  auto [poisson, density] = open3d::geometry::TriangleMesh::CreateFromPointCloudPoisson(points, options.poisson_depth, 0.f, 1.1f, false, 1);
  require(poisson && !poisson->triangles_.empty(), "initial mesh: Poisson reconstruction produced no surface");

  // Drop small islands Poisson sometimes leaves around sparse rims.
  auto [cluster, cluster_faces, cluster_area] = poisson->ClusterConnectedTriangles();
  std::vector<bool> drop(poisson->triangles_.size(), false);
  for (size_t f = 0; f < drop.size(); ++f)
    drop[f] = double(cluster_faces[cluster[f]]) < options.min_component_fraction * double(drop.size());
  poisson->RemoveTrianglesByMask(drop);
  poisson->RemoveUnreferencedVertices();

  t_poisson.finish();
  StageTimer t_simplify("initial mesh: decimating " + std::to_string(poisson->triangles_.size()) + " faces");
  auto simplified = poisson->SimplifyQuadricDecimation(options.target_faces, std::numeric_limits<double>::infinity(), 1.0);
  simplified->RemoveDegenerateTriangles();
  simplified->RemoveDuplicatedTriangles();
  simplified->RemoveDuplicatedVertices();
  simplified->RemoveNonManifoldEdges();
  simplified->RemoveUnreferencedVertices();

  Mesh mesh = from_open3d(*simplified);
  require(!mesh.faces.empty(), "initial mesh: decimation left no faces");
  // Removing the non-manifold edges opens small holes (19 border edges on Spot): the optimisation
  // stages and their back-face culling need a closed, outward surface.
  repair_to_closed_manifold(mesh);
  return mesh;
}

}  // namespace u3d
