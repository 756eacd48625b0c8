// ISOMER stage costs at the pipeline's 512 px: one differentiable render + loss + backward of the four
// views, one remeshing pass, and the two full stages on a synthetic shape (exact normal maps of a
// bulged ellipsoid, coarse stage from the sphere, refinement on its result); and the normal
// integration of the initial mesh (the pipeline's 192 px, and 256 and 512) on a hemisphere's normals.
#include <benchmark/benchmark.h>

#include <cmath>

#include "core/progress.h"
#include "geometry/icosphere.h"
#include "isomer/coarse_stage.h"
#include "isomer/mesh_optimizer.h"
#include "isomer/normal_integration.h"
#include "isomer/normal_renderer.h"
#include "isomer/reconstruction_losses.h"
#include "isomer/refine_stage.h"

using namespace u3d;

namespace {

Mesh bulged_ellipsoid() {
  Mesh m = make_icosphere(4, 1.f);
  for (Vec3f& p : m.positions) {
    const float bump = 0.25f * std::exp(-((p - Vec3f(0.6f, 0.3f, 0.75f)).squaredNorm()) / 0.15f);
    p = Vec3f(0.7f * p.x(), 0.55f * p.y(), 0.4f * p.z()) * (1.f + bump);
  }
  return m;
}

std::vector<Camera> cameras(int res) {
  std::vector<Camera> c;
  for (View v : kAllViews) c.push_back(view_camera(v, res));
  return c;
}

std::vector<Image> normal_maps(const Mesh& mesh, const std::vector<Camera>& cams) {
  NormalRenderer r(cams);
  r.render(mesh.positions, mesh.faces, build_edge_topology(mesh.faces, mesh.positions.size()),
           compute_vertex_normals(mesh.positions, mesh.faces).unit);
  std::vector<Image> maps;
  for (size_t i = 0; i < cams.size(); ++i) maps.push_back(r.view(i).image);
  return maps;
}

}  // namespace

static void BM_RenderLossBackward512(benchmark::State& state) {
  const Mesh mesh = bulged_ellipsoid();
  const auto cams = cameras(512);
  std::vector<NormalTarget> targets;
  for (const Image& m : normal_maps(mesh, cams)) targets.push_back(make_normal_target(m));
  std::vector<const Image*> refs;
  for (const NormalTarget& t : targets) refs.push_back(&t.rgba);
  const Mesh current = make_icosphere(int(state.range(0)), 0.6f);
  const EdgeTopology topology = build_edge_topology(current.faces, current.positions.size());
  NormalRenderer r(cams);
  std::vector<Vec3f> grad;
  for (auto _ : state) {
    const VertexNormals n = compute_vertex_normals(current.positions, current.faces);
    r.render(current.positions, current.faces, topology, n.unit);
    grad.assign(current.positions.size(), Vec3f::Zero());
    benchmark::DoNotOptimize(masked_image_l2(r, refs, 4, 1.f) + background_alpha_l2(r, targets, 1.f));
    r.backward(current.positions, current.faces, n, grad);
  }
  state.counters["faces"] = double(current.faces.size());
}
BENCHMARK(BM_RenderLossBackward512)->Arg(4)->Arg(6)->Unit(benchmark::kMillisecond);

static void BM_RemeshPass(benchmark::State& state) {
  const Mesh sphere = make_icosphere(int(state.range(0)), 0.8f);
  MeshOptimizerOptions o;
  o.max_edge_length = o.min_edge_length = 0.02f;
  MeshOptimizer opt(sphere.positions, sphere.faces, o);
  for (auto _ : state) benchmark::DoNotOptimize(opt.remesh());
  state.counters["vertices"] = double(opt.positions().size());
}
BENCHMARK(BM_RemeshPass)->Arg(5)->Unit(benchmark::kMillisecond);

static void BM_Stages512(benchmark::State& state) {
  set_progress_quiet(true);
  const Mesh truth = bulged_ellipsoid();
  const auto cams = cameras(512);
  const auto maps = normal_maps(truth, cams);
  RefineStageOptions refine;
  refine.max_vertices = size_t(state.range(0));
  for (auto _ : state) {
    StageReport coarse_report, refine_report;
    const Mesh coarse = run_coarse_stage(sphere_initial_mesh(), {maps, cams}, CoarseStageOptions::from_sphere(),
                                         &coarse_report);
    const Mesh refined = run_refine_stage(coarse, {maps, cams}, refine, &refine_report);
    state.counters["coarse_s"] = coarse_report.seconds;
    state.counters["refine_s"] = refine_report.seconds;
    state.counters["vertices"] = double(refined.positions.size());
  }
}
BENCHMARK(BM_Stages512)->Arg(20000)->Iterations(1)->Unit(benchmark::kSecond);

// The normals of a hemisphere filling most of a size x size map (96 rotations, the official count).
static void BM_NormalIntegration(benchmark::State& state) {
  const int size = int(state.range(0));
  const float radius = 0.49f * size, rim = 0.47f * size, c = 0.5f * (size - 1);
  std::vector<Vec3f> normals(size_t(size) * size, Vec3f(0, 0, 1));
  std::vector<uint8_t> mask(normals.size(), 0);
  for (int v = 0; v < size; ++v)
    for (int u = 0; u < size; ++u) {
      const float x = u - c, y = c - v;
      if (x * x + y * y > rim * rim) continue;
      normals[size_t(v) * size + u] = Vec3f(x, y, std::sqrt(radius * radius - x * x - y * y)).normalized();
      mask[size_t(v) * size + u] = 1;
    }
  for (auto _ : state) benchmark::DoNotOptimize(integrate_normal_map(normals, mask, size, size));
}
BENCHMARK(BM_NormalIntegration)->Arg(192)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
