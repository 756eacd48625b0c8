// Full ISOMER reconstruction of the bundled example (examples/spot/spot.obj) from its four views rendered
// in memory at each requested normal-map resolution (default 512 and 2048 px), as `unique3d render`
// renders them (fill 0.9, 2x supersampling, world normals). Prints the time of every stage, the total,
// the face count and the peak resident memory. Each resolution runs in its own child process so the
// peak memory (getrusage ru_maxrss) is that resolution's alone. Not a Google Benchmark: one run each.
// Usage: bench_isomer [RESOLUTION...]
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/memory.h"
#include "core/progress.h"
#include "geometry/mesh_topology.h"
#include "io/mesh_io.h"
#include "isomer/reconstruct.h"
#include "isomer/silhouette_check.h"
#include "render/render_view.h"

using namespace u3d;

namespace {

ViewSet render_spot_views(int resolution) {
  Mesh mesh = read_mesh(std::filesystem::path(UNIQUE3D_SOURCE_DIR) / "examples/spot/spot.obj");
  normalize_to_unit_box(mesh, 0.9f);
  RenderSettings settings;
  settings.ssaa = resolution <= 4096 ? 2 : 1;
  std::array<Image, 4> rgb, normals;
  std::array<std::string, 4> rgb_names, normal_names;
  for (View v : kAllViews) {
    RenderedView r = render_view(mesh, view_camera(v, resolution), settings);
    rgb[size_t(v)] = std::move(r.rgb);
    normals[size_t(v)] = std::move(r.normal);
    rgb_names[size_t(v)] = view_file_name(v, false);
    normal_names[size_t(v)] = view_file_name(v, true);
  }
  return make_view_set(std::move(rgb), std::move(normals), NormalSpace::World, rgb_names, normal_names);
}

void run_one(int resolution) {
  set_progress_quiet(true);
  const ViewSet views = render_spot_views(resolution);
  const ReconstructResult result = reconstruct(views);
  const std::array<float, 4> iou = silhouette_iou(result.mesh, views);
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  double total = 0.0;
  std::printf("%5d px:", resolution);
  for (const StageTiming& t : result.timings) {
    std::printf(" %s %.2f s,", t.name.c_str(), t.seconds);
    total += t.seconds;
  }
  // CPU time of all threads, including rendering the views: comparable across runs on a shared machine.
  const double cpu = double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                     1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  std::printf(" total %.2f s (process CPU %.1f s) | %zu faces, %s | IoU %.3f %.3f %.3f %.3f | peak RSS %.0f MiB\n",
              total, cpu,
              result.mesh.face_count(), mesh_topology(result.mesh).summary().c_str(), iou[0], iou[1], iou[2], iou[3],
              double(usage.ru_maxrss) / 1024.0);
  for (const auto& [name, report] : {std::pair{"coarse", &result.coarse}, std::pair{"refine", &result.refine}}) {
    const StageProfile& p = report->profile;
    std::printf("         %s profile: render %.2f s, losses %.2f s, backward %.2f s, step %.2f s, remesh %.2f s\n",
                name, p.render, p.losses, p.backward, p.step, p.remesh);
  }
  std::printf("         texture: UV atlas %.2f s, baking %.2f s, %d charts, %.1f %% of the texels used\n",
              result.texture.uv_seconds, result.texture.bake_seconds, result.texture.charts,
              100.0 * result.texture.texel_efficiency);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  keep_freed_memory_for_reuse();  // as the CLI does
  std::vector<int> resolutions;
  for (int i = 1; i < argc; ++i) resolutions.push_back(std::atoi(argv[i]));
  if (resolutions.empty()) resolutions = {512, 2048};
  int failures = 0;
  for (int res : resolutions) {
    if (res < 64 || res > 8192) {
      std::fprintf(stderr, "bench_isomer: resolution %d out of range [64, 8192]\n", res);
      return 2;
    }
    const pid_t child = fork();
    if (child == 0) {
      try {
        run_one(res);
        _exit(0);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_isomer: %d px: %s\n", res, e.what());
        _exit(1);
      }
    }
    int status = 0;
    waitpid(child, &status, 0);
    failures += !(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  }
  return failures == 0 ? 0 : 1;
}
