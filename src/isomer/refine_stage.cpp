#include "isomer/refine_stage.h"

#include "core/progress.h"
#include "isomer/mesh_optimizer.h"
#include "isomer/optimisation_loop.h"
#include "isomer/reconstruction_losses.h"

namespace u3d {

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
  std::vector<Image> target_images(cameras.size());
  std::vector<const Image*> references;
  if (options.use_explicit_target) {
    for (const Image& img : target_images) references.push_back(&img);
  } else {
    for (const NormalTarget& t : targets) references.push_back(&t.rgba);
  }
  auto losses = [&](int step, const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                    const VertexNormals& normals, std::vector<Vec3f>& grad) {
    if (options.use_explicit_target &&
        (step < options.update_warmup || step % std::max(options.update_interval, 1) == 0)) {
      std::vector<const RasterBuffer*> rasters;
      for (size_t i = 0; i < cameras.size(); ++i) rasters.push_back(&renderer.view(i).raster);
      const std::vector<Vec3f> et = explicit_target_normals(positions, faces, normals.unit, normal_maps, cameras,
                                                            rasters, options.explicit_target);
      // The targets are rendered once here and then held fixed while the mesh moves.
      for (size_t i = 0; i < cameras.size(); ++i) renderer.render_attribute(faces, et, i, target_images[i]);
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
