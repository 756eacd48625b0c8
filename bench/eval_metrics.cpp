// Speed of the geometry metrics on an 81,920-face sphere (a typical reconstruction size): surface
// sampling, hierarchy build, 2 x 100k closest-point queries, occupancy grids by winding numbers.
#include <benchmark/benchmark.h>

#include "../tests/geometry/test_shapes.h"
#include "core/parallel.h"
#include "eval/chamfer.h"
#include "eval/volume_iou.h"
#include "geometry/surface_sampling.h"
#include "geometry/triangle_bvh.h"

using namespace u3d;

namespace {

const Mesh& big_sphere() {
  static const Mesh m = test::sphere_mesh(0.45f, 6);
  return m;
}

void BM_SampleSurface(benchmark::State& state) {
  for (auto _ : state)
    benchmark::DoNotOptimize(sample_surface(big_sphere().positions, big_sphere().faces, state.range(0), 1));
}

void BM_BuildBvh(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(TriangleBvh(big_sphere().positions, big_sphere().faces));
}

void BM_SurfaceDistances(benchmark::State& state) {
  static const Mesh other = test::sphere_mesh(0.4f, 6);
  for (auto _ : state) benchmark::DoNotOptimize(surface_distances(big_sphere(), other, state.range(0), 1));
}

void BM_OccupancyGrid(benchmark::State& state) {
  Eigen::AlignedBox3f box(Vec3f::Constant(-0.5f), Vec3f::Constant(0.5f));
  for (auto _ : state) benchmark::DoNotOptimize(occupancy_grid(big_sphere(), box, int(state.range(0))));
}

}  // namespace

BENCHMARK(BM_SampleSurface)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BuildBvh)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SurfaceDistances)->Arg(100000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_OccupancyGrid)->Arg(64)->Arg(128)->Unit(benchmark::kMillisecond)->UseRealTime();

int main(int argc, char** argv) {
  configure_threads();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
