// UV atlas and texture baking at the sizes `reconstruct --colour texture` uses by default: the bundled
// spot, subdivided and decimated to 40k faces (as the pipeline's final decimation leaves it), baked
// into a 2048^2 texture from its four views rendered at 2048 px. Wall and process CPU time: on the shared
// machine the wall time follows the load, the CPU time (both cores together) much less.
#include <benchmark/benchmark.h>

#include "geometry/loop_subdivision.h"
#include "geometry/quadric_decimation.h"
#include "geometry/uv_atlas.h"
#include "io/mesh_io.h"
#include "isomer/texture_bake.h"
#include "render/render_view.h"

using namespace u3d;

namespace {

constexpr size_t kFaces = 40000;
constexpr int kSize = 2048;

const Mesh& textured_spot() {
  static const Mesh mesh = [] {
    Mesh m = read_mesh(std::string(UNIQUE3D_SOURCE_DIR) + "/examples/spot/spot.obj");
    normalize_to_unit_box(m, 0.9f);
    return m;
  }();
  return mesh;
}

const Mesh& spot_40k() {
  static const Mesh mesh = [] {
    Mesh geometry;
    geometry.positions = textured_spot().positions;
    geometry.faces = textured_spot().faces;
    return decimate_closed_mesh(loop_subdivide(loop_subdivide(geometry)), kFaces);
  }();
  return mesh;
}

const ViewSet& spot_views() {
  static const ViewSet views = [] {
    ViewSet v;
    for (View view : kAllViews) v[view].rgb = render_view(textured_spot(), view_camera(view, kSize)).rgb;
    return v;
  }();
  return views;
}

void BM_AxisChartAtlas(benchmark::State& state) {
  const Mesh& mesh = spot_40k();
  UvAtlas atlas;
  for (auto _ : state) atlas = axis_chart_atlas(mesh);
  state.counters["faces"] = double(mesh.face_count());
  state.counters["charts"] = atlas.chart_count;
  state.counters["texel_efficiency"] = atlas.texel_efficiency;
  state.counters["seam_vertices"] = double(atlas.mesh.vertex_count()) / double(mesh.vertex_count());
}
BENCHMARK(BM_AxisChartAtlas)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

// The whole texture stage: atlas, vertex colouring, per-texel ExplicitTarget from 2048 px views, dilation.
void BM_BakeTexture(benchmark::State& state) {
  const ViewSet& views = spot_views();
  TextureBakeReport report;
  for (auto _ : state) {
    Mesh mesh = spot_40k();
    report = bake_texture(mesh, views);
  }
  state.counters["uv_s"] = report.uv_seconds;
  state.counters["bake_s"] = report.bake_seconds;
  state.counters["texel_efficiency"] = report.texel_efficiency;
}
BENCHMARK(BM_BakeTexture)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime()->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
