// Rasterizer throughput on bumpy spheres of 100k and 1M faces at 512 and 2048 pixels, front view.
// Counters: megapixels/s (image pixels) and faces/s (input faces).
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <random>

#include "render/rasterizer.h"
#include "render/render_view.h"

using namespace u3d;

namespace {

// UV sphere of radius 0.9 with about `faces` triangles, each vertex displaced radially by up to a
// fifth of an edge length (so depth and normals vary but the surface stays a sensible mesh).
const Mesh& bumpy_sphere(int faces) {
  static std::map<int, Mesh> cache;
  auto it = cache.find(faces);
  if (it != cache.end()) return it->second;
  Mesh m;
  const int rings = std::max(2, int(std::sqrt(faces / 4.0)));
  const int segments = std::max(3, faces / (2 * rings));
  std::mt19937 rng(1);
  const float edge = 2.f * float(M_PI) / float(segments);
  std::uniform_real_distribution<float> bump(1.f - 0.2f * edge, 1.f + 0.2f * edge);
  for (int r = 0; r <= rings; ++r) {
    float theta = float(M_PI) * r / rings;
    for (int s = 0; s < segments; ++s) {
      float phi = 2.f * float(M_PI) * s / segments;
      float radius = 0.9f * bump(rng);
      m.positions.push_back(radius * Vec3f(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)));
    }
  }
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      int a = r * segments + s, b = r * segments + (s + 1) % segments, c = a + segments, d = b + segments;
      m.faces.push_back({a, c, b});
      m.faces.push_back({b, c, d});
    }
  return cache.emplace(faces, std::move(m)).first->second;
}

void set_counters(benchmark::State& state, const Mesh& mesh, int res) {
  state.counters["MPix/s"] = benchmark::Counter(double(res) * res * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["faces/s"] = benchmark::Counter(double(mesh.face_count()), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_Rasterize(benchmark::State& state) {
  const Mesh& mesh = bumpy_sphere(int(state.range(0)));
  const int res = int(state.range(1));
  Camera cam = view_camera(View::Front, res);
  for (auto _ : state) {
    RasterBuffer buf = rasterize(mesh, cam);
    benchmark::DoNotOptimize(buf.face_id.data());
  }
  set_counters(state, mesh, res);
}

// Frame after frame into the same buffer with back faces culled, as the optimisation stages draw each
// view (run with OMP_NUM_THREADS=1 to see one view's cost on one thread, as there).
void BM_RasterizeFrames(benchmark::State& state) {
  const Mesh& mesh = bumpy_sphere(int(state.range(0)));
  const int res = int(state.range(1));
  const Camera cam = view_camera(View::Front, res);
  RasterBuffer buf;
  for (auto _ : state) {
    rasterize_into(mesh.positions, mesh.faces, cam, buf, RasterOptions{.cull_backfaces = true});
    benchmark::DoNotOptimize(buf.face_id.data());
  }
  set_counters(state, mesh, res);
}

// The whole reference render: rasterize + RGB and normal shading (no supersampling).
void BM_RenderView(benchmark::State& state) {
  const Mesh& mesh = bumpy_sphere(int(state.range(0)));
  const int res = int(state.range(1));
  Camera cam = view_camera(View::Front, res);
  for (auto _ : state) {
    RenderedView view = render_view(mesh, cam, RenderSettings{});
    benchmark::DoNotOptimize(view.rgb.data.data());
  }
  set_counters(state, mesh, res);
}

}  // namespace

BENCHMARK(BM_Rasterize)->ArgsProduct({{100000, 1000000}, {512, 2048}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RasterizeFrames)->ArgsProduct({{40000, 160000}, {512}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderView)->ArgsProduct({{100000, 1000000}, {512, 2048}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_MAIN();
