// The normal renderer culls back faces: on a closed, outward-oriented surface that must change no pixel.
#include <gtest/gtest.h>

#include "isomer/icosphere.h"
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
  renderer.render(mesh.positions, mesh.faces, normals.unit);
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

}  // namespace
}  // namespace u3d
