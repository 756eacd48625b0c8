// The normal renderer culls back faces: on a closed, outward-oriented surface that must change no pixel.
// It also counts each frame's opaque pixels for the losses.
#include <gtest/gtest.h>

#include "geometry/icosphere.h"
#include "isomer/normal_renderer.h"

namespace u3d {
namespace {

TEST(NormalRenderer, CullingChangesNoPixelOfAClosedSurface) {
  Mesh mesh = make_icosphere(3, 0.8f);
  for (Vec3f& p : mesh.positions) p = Vec3f(1.1f * p.x() + 0.1f, 0.7f * p.y(), p.z() + 0.3f * p.x() * p.y());
  std::vector<Camera> cameras;
  for (View v : kAllViews) cameras.push_back(view_camera(v, 96));
  cameras.push_back(perspective_camera(3.f * orbit_direction(40.f, 25.f), 96, 96, 40.f));
  NormalRenderer renderer(cameras);
  const VertexNormals normals = compute_vertex_normals(mesh.positions, mesh.faces);
  renderer.render(mesh.positions, mesh.faces, build_edge_topology(mesh.faces, mesh.positions.size()), normals.unit);
  for (size_t i = 0; i < cameras.size(); ++i) {
    const RasterBuffer all = rasterize(mesh, cameras[i]);
    const RasterBuffer& culled = renderer.view(i).raster;
    size_t covered = 0;
    for (size_t p = 0; p < all.pixel_count(); ++p) {
      covered += all.covered(p);
      ASSERT_EQ(culled.face_id[p], all.face_id[p]) << "view " << i << " pixel " << p;
    }
    EXPECT_GT(covered, 1000u) << "view " << i;
  }
}

TEST(NormalRenderer, CountsTheOpaquePixelsOfEveryFrame) {
  // The count is kept from the blends alone; it must match a scan of the image over two frames, so
  // the second one also checks that the first left no pixel marked.
  Mesh mesh = make_icosphere(3, 0.7f);
  std::vector<Camera> cameras;
  for (View v : kAllViews) cameras.push_back(view_camera(v, 80));
  NormalRenderer renderer(cameras);
  for (float shift : {0.f, 0.137f}) {
    for (Vec3f& p : mesh.positions) p.x() += shift;
    const VertexNormals normals = compute_vertex_normals(mesh.positions, mesh.faces);
    renderer.render(mesh.positions, mesh.faces, build_edge_topology(mesh.faces, mesh.positions.size()), normals.unit);
    for (size_t i = 0; i < cameras.size(); ++i) {
      const DifferentiableView& v = renderer.view(i);
      size_t opaque = 0, partial = 0;
      for (size_t p = 0; p < v.image.pixel_count(); ++p) {
        const float alpha = v.image.data[p * 4 + 3];
        opaque += alpha > 0.5f;
        partial += alpha > 0.f && alpha < 1.f;
      }
      EXPECT_EQ(v.opaque_pixels, opaque) << "view " << i;
      EXPECT_GT(partial, 20u) << "view " << i;  // the silhouette is blended
      for (uint8_t mark : v.listed) ASSERT_EQ(mark, 0);
    }
  }
}

}  // namespace
}  // namespace u3d
