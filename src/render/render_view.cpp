#include "render/render_view.h"

#include "core/error.h"
#include "render/rasterizer.h"
#include "render/supersample.h"

namespace u3d {

RenderedView render_view(const Mesh& mesh, const Camera& camera, const RenderSettings& settings) {
  require(settings.ssaa >= 1 && settings.ssaa <= 8, "ssaa factor must be between 1 and 8, got " + std::to_string(settings.ssaa));
  mesh.validate("render_view");
  // The projection maps to normalized device coordinates, so a finer image is the same camera with more pixels.
  Camera fine = camera;
  fine.width = camera.width * settings.ssaa;
  fine.height = camera.height * settings.ssaa;
  RasterBuffer buf = rasterize(mesh, fine, RasterOptions{settings.cull_backfaces});
  RenderedView view;
  view.rgb = shade_colors(buf, mesh);
  if (settings.smooth_normals) {
    view.normal = shade_vertex_normals(buf, mesh.positions, mesh.faces, vertex_normals(mesh.positions, mesh.faces),
                                       fine, settings.normal_space);
  } else {
    view.normal = shade_face_normals(buf, face_normals(mesh.positions, mesh.faces), fine, settings.normal_space);
  }
  view.rgb = downsample_alpha_weighted(view.rgb, settings.ssaa);
  view.normal = downsample_alpha_weighted(view.normal, settings.ssaa);
  return view;
}

}  // namespace u3d
