#include "isomer/refine_stage.h"

#include "core/progress.h"
#include "isomer/mesh_optimizer.h"
#include "isomer/optimisation_loop.h"
#include "isomer/reconstruction_losses.h"

namespace u3d {
namespace {

// The target of one view where ExplicitTarget applies only in part: at each covered pixel, with f the
// per-vertex `fused` flag interpolated over the raster,
//   target = f * c_et * a + (1 - f) * view_target,
// c_et the interpolated ExplicitTarget colour (n + 1) / 2, a the view's own alpha and view_target its
// premultiplied map. Off the footprint the view's map applies. So the silhouettes always come from the
// views, never from the mesh at the last update.
void partly_fused_target(const RasterBuffer& raster, const std::vector<Vec3i>& faces,
                         const std::vector<Vec3f>& et_normals, const std::vector<float>& fused,
                         const Image& view_target, Image& target) {
  target = view_target;
  for (size_t p = 0; p < raster.pixel_count(); ++p) {
    if (!raster.covered(p)) continue;
    const Vec3i& face = faces[size_t(raster.face_id[p])];
    const Vec2f b = raster.bary[p];
    const float w[3] = {1.f - b.x() - b.y(), b.x(), b.y()};
    float f = 0.f;
    Vec3f normal = Vec3f::Zero();
    for (int k = 0; k < 3; ++k) {
      f += w[k] * fused[size_t(face[k])];
      normal += w[k] * et_normals[size_t(face[k])];
    }
    if (f <= 0.f) continue;
    float* out = target.data.data() + p * 4;
    const float alpha = out[3];
    for (int c = 0; c < 3; ++c) out[c] = f * 0.5f * (normal[c] + 1.f) * alpha + (1.f - f) * out[c];
  }
}

}  // namespace

Mesh run_refine_stage(const Mesh& coarse, const NormalViews& input, const RefineStageOptions& options,
                      StageReport* report) {
  StageTimer timer("mesh refinement");
  const NormalViews views = prepare_stage_views("refine stage", input, options.render_resolution);
  const std::vector<Image>& normal_maps = views.normal_maps;
  const std::vector<Camera>& cameras = views.cameras;
  const std::vector<NormalTarget> targets = normal_targets(views);

  MeshOptimizerOptions opt;
  opt.learning_rate = options.learning_rate;
  opt.min_edge_length = options.end_edge_length;
  opt.max_edge_length = options.start_edge_length;
  opt.ramp = options.ramp;
  opt.gain = options.gain;
  opt.local_edge_length = false;
  opt.max_vertices = options.max_vertices;
  opt.seed = options.seed;
  MeshOptimizer optimizer(coarse.positions, coarse.faces, opt);
  NormalRenderer renderer(cameras);
  const bool fuse = options.target != RefineTarget::MultiView;
  std::vector<Image> target_images(cameras.size());
  std::vector<const Image*> references;
  for (size_t i = 0; i < cameras.size(); ++i) references.push_back(fuse ? &target_images[i] : &targets[i].rgba);
  std::vector<float> fused;  // per vertex: 1 where the ExplicitTarget applies
  auto losses = [&](int step, const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                    const VertexNormals& normals, std::vector<Vec3f>& grad) {
    if (fuse && (step < options.update_warmup || step % std::max(options.update_interval, 1) == 0)) {
      std::vector<const RasterBuffer*> rasters;
      for (size_t i = 0; i < cameras.size(); ++i) rasters.push_back(&renderer.view(i).raster);
      const ExplicitTargetNormals et = explicit_target_normals(positions, faces, normals.unit, normal_maps, cameras,
                                                               rasters, options.explicit_target);
      // The targets are rendered once here and then held fixed while the mesh moves.
      if (options.target == RefineTarget::ExplicitTarget) {
        for (size_t i = 0; i < cameras.size(); ++i) renderer.render_attribute(faces, et.normals, i, target_images[i]);
      } else {
        fused.resize(positions.size());
        for (size_t v = 0; v < positions.size(); ++v)
          fused[v] = et.disagreement[v] > options.disagreement_threshold ? 1.f : 0.f;
        for (size_t i = 0; i < cameras.size(); ++i)
          partly_fused_target(renderer.view(i).raster, faces, et.normals, fused, targets[i].rgba, target_images[i]);
      }
    }
    double loss = masked_image_l2(renderer, references, 3, 1.f);
    loss += background_alpha_l2(renderer, targets, 1.f);
    loss += out_of_box_loss(positions, options.out_of_box_limit, options.out_of_box_weight, grad);
    return loss;
  };
  run_optimisation_loop("mesh refinement", optimizer, renderer, options.steps, options.lr_decay, losses, report);
  if (report) report->seconds = timer.finish();
  return optimizer.mesh();
}

}  // namespace u3d
