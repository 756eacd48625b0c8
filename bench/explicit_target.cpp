// ExplicitTarget ablation in one process (issue 22): for each object, render its four views as
// `unique3d render --fill 0.9` does, optionally perturb them as `unique3d perturb` does, reconstruct
// with each refinement target (multi-view loss, ExplicitTarget everywhere, ExplicitTarget where the
// views disagree) and evaluate in the views' frame as `unique3d eval --given-frame --gt-render-fill
// 0.9` does. Besides CD-L1 and PSNR it reports, per vertex of the prediction, the normal error and the
// signed offset from the GT surface, split into surfaces facing the side views and those facing up or
// down, and writes the prediction coloured by its normal error (<target>_normal_error.ply, the error
// map). Needs no network code, so it builds and runs without libtorch's objects.
//
//   bench_explicit_target --only spot,bob [--res 512] [--warp 2:128] [--bend 4:256] [--shading 0.05:128]
//                         [--targets multiview,explicit,disagree] [--threshold 0.1] [--out DIR]
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include "core/error.h"
#include "core/progress.h"
#include "eval/evaluate.h"
#include "eval/view_perturbation.h"
#include "geometry/triangle_bvh.h"
#include "io/mesh_io.h"
#include "isomer/reconstruct.h"
#include "render/render_view.h"

using namespace u3d;
namespace fs = std::filesystem;

namespace {

constexpr float kFill = 0.9f;

SmoothFieldSpec parse_field(const std::string& spec) {
  if (spec.empty()) return {};
  const auto colon = spec.find(':');
  require(colon != std::string::npos, "field spec must be AMPLITUDE:SCALE, got " + spec);
  return {std::stof(spec.substr(0, colon)), std::stof(spec.substr(colon + 1))};
}

struct SurfaceError {
  double side_angle = 0, vertical_angle = 0, side_offset = 0, vertical_offset = 0;
  size_t side = 0, vertical = 0;
};

// pred and gt already in the evaluation frame. Colours pred by the angle error (black 0 degrees, red
// 10, yellow 20 and more): the error map.
SurfaceError surface_error(Mesh& pred, const Mesh& gt) {
  const TriangleBvh bvh(gt.positions, gt.faces);
  const std::vector<Vec3f> gt_normals = face_normals(gt.positions, gt.faces);
  const std::vector<Vec3f> normals = vertex_normals(pred.positions, pred.faces);
  SurfaceError e;
  pred.colors.assign(pred.positions.size(), Vec3f(0, 0, 0));
  for (size_t v = 0; v < pred.positions.size(); ++v) {
    const TriangleBvh::Closest c = bvh.closest_point(pred.positions[v]);
    const Vec3f& n = gt_normals[size_t(c.face)];
    const double angle = std::acos(std::clamp(normals[v].dot(n), -1.f, 1.f)) * 180.0 / M_PI;
    const double offset = (pred.positions[v] - c.point).dot(n) >= 0 ? c.distance : -c.distance;
    if (std::abs(n.y()) < 0.5f) e.side_angle += angle, e.side_offset += offset, ++e.side;
    else e.vertical_angle += angle, e.vertical_offset += offset, ++e.vertical;
    const float t = std::min(float(angle) / 20.f, 1.f);
    pred.colors[v] = Vec3f(std::min(2 * t, 1.f), std::max(2 * t - 1, 0.f), 0);
  }
  if (e.side) e.side_angle /= double(e.side), e.side_offset /= double(e.side);
  if (e.vertical) e.vertical_angle /= double(e.vertical), e.vertical_offset /= double(e.vertical);
  return e;
}

fs::path find_mesh(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".obj" || ext == ".glb" || ext == ".ply" || ext == ".gltf") return e.path();
  }
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"ExplicitTarget ablation on rendered objects, in one process"};
  std::string objects_dir = (fs::path(UNIQUE3D_SOURCE_DIR) / ".." / "shared" / "data" / "objects").string();
  std::string out_dir = "bench_explicit_target_out", warp, bend, shading;
  std::vector<std::string> only, targets = {"multiview", "explicit", "disagree"};
  int resolution = 512;
  uint64_t seed = 1;
  float threshold = RefineStageOptions{}.disagreement_threshold;
  app.add_option("--objects", objects_dir)->capture_default_str();
  app.add_option("--out", out_dir)->capture_default_str();
  app.add_option("--only", only)->delimiter(',');
  app.add_option("--res", resolution)->capture_default_str();
  app.add_option("--warp", warp, "as `unique3d perturb --warp`");
  app.add_option("--bend", bend, "as `unique3d perturb --bend`");
  app.add_option("--shading", shading, "as `unique3d perturb --shading`");
  app.add_option("--seed", seed)->capture_default_str();
  app.add_option("--targets", targets)->delimiter(',')->check(CLI::IsMember({"multiview", "explicit", "disagree"}));
  app.add_option("--threshold", threshold)->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  set_progress_quiet(true);
  try {
    const std::map<std::string, RefineTarget> modes = {{"multiview", RefineTarget::MultiView},
                                                       {"explicit", RefineTarget::ExplicitTarget},
                                                       {"disagree", RefineTarget::WhereViewsDisagree}};
    std::vector<fs::path> objects;
    for (const auto& e : fs::directory_iterator(objects_dir))
      if (e.is_directory() && (only.empty() || std::find(only.begin(), only.end(), e.path().filename()) != only.end()))
        objects.push_back(e.path());
    std::sort(objects.begin(), objects.end());
    std::printf("| object | target | CD-L1 | PSNR | SSIM | side angle | side offset | up/down angle | up/down offset | up/down share |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
    std::map<std::string, std::array<double, 4>> sums;  // cd, psnr, ssim, count
    for (const fs::path& obj : objects) {
      const fs::path mesh_path = find_mesh(obj);
      if (mesh_path.empty()) continue;
      Mesh gt = read_mesh(mesh_path);
      Mesh placed = gt;
      normalize_to_unit_box(placed, kFill);
      const fs::path dir = fs::path(out_dir) / obj.filename();
      fs::create_directories(dir / "views");
      RenderSettings settings;
      settings.ssaa = 2;  // `unique3d render`'s default
      for (View v : kAllViews) {
        RenderedView r = render_view(placed, view_camera(v, resolution), settings);
        save_image(r.rgb, dir / "views" / (std::string(view_name(v)) + "_rgb.png"));
        save_image(r.normal, dir / "views" / (std::string(view_name(v)) + "_normal.png"));
      }
      fs::path views_dir = dir / "views";
      PerturbOptions perturb;
      perturb.displacement = parse_field(warp);
      perturb.bend = parse_field(bend);
      perturb.shading = parse_field(shading);
      perturb.seed = seed;
      if (perturb.displacement.active() || perturb.bend.active() || perturb.shading.active()) {
        fs::remove_all(dir / "perturbed");
        perturb_view_set(views_dir, dir / "perturbed", perturb);
        views_dir = dir / "perturbed";
      }
      const ViewSet views = load_view_set(views_dir);
      for (const std::string& target : targets) {
        ReconstructOptions options;
        options.refine.target = modes.at(target);
        options.refine.disagreement_threshold = threshold;
        Mesh pred = reconstruct(views, options).mesh;
        write_mesh(pred, dir / (target + ".glb"));
        EvalOptions eval;
        eval.normalize = false;
        eval.gt_render_fill = kFill;
        const EvalReport report = evaluate_meshes(pred, gt, eval);
        // The frame evaluate_meshes used, for the per-vertex errors.
        Mesh gt_frame = gt;
        normalize_to_unit_box(gt_frame, kFill);
        const Similarity s = normalize_to_unit_box(gt_frame, 0.5f);
        for (Vec3f& p : pred.positions) p = s.scale * (p + s.offset);
        const SurfaceError e = surface_error(pred, gt_frame);
        write_mesh(pred, dir / (target + "_normal_error.ply"));
        const double psnr = report.appearance ? report.appearance->psnr : 0.0;
        const double ssim = report.appearance ? report.appearance->ssim : 0.0;
        std::printf("| %s | %s | %.5f | %.2f | %.4f | %.2f | %+.5f | %.2f | %+.5f | %.3f |\n",
                    obj.filename().c_str(), target.c_str(), report.chamfer.chamfer_l1, psnr, ssim, e.side_angle,
                    e.side_offset, e.vertical_angle, e.vertical_offset,
                    double(e.vertical) / double(std::max<size_t>(e.side + e.vertical, 1)));
        std::fflush(stdout);
        auto& sum = sums[target];
        sum[0] += report.chamfer.chamfer_l1, sum[1] += psnr, sum[2] += ssim, sum[3] += 1;
      }
    }
    for (const auto& [target, sum] : sums)
      std::printf("| mean (%d) | %s | %.5f | %.2f | %.4f | | | | | |\n", int(sum[3]), target.c_str(), sum[0] / sum[3],
                  sum[1] / sum[3], sum[2] / sum[3]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_explicit_target: %s\n", e.what());
    return 1;
  }
  return 0;
}
