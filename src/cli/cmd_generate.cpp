// `unique3d generate PHOTO -o mesh.glb --models M`: the whole method, photo to textured mesh, through
// the library facade (pipeline/generate.h); this file parses options and prints the summary.
#include <cstdio>
#include <fstream>

#include "cli/command.h"
#include "cli/isomer_options.h"
#include "cli/mesh_output_options.h"
#include "cli/network_options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "pipeline/generate.h"
#include "pipeline/summary_json.h"

namespace u3d::cli {
namespace {

struct GenerateArgs {
  GenerateRequest request;
  NetworkArgs network;
  bool no_refine = false;
  int steps = 0;  // 0: each stage's own
  std::string json_path;
  IsomerStepArgs isomer;
  MeshOutputArgs output;
};

void run(const GenerateArgs& a) {
  GenerateRequest request = a.request;
  request.network = a.network.resolved();
  request.refine = !a.no_refine;
  if (a.steps > 0) request.multiview.steps = request.normals.steps = a.steps;
  apply_isomer_step_options(a.isomer, request.reconstruct);
  apply_mesh_output_options(a.output, request.reconstruct, request.texture_format);
  const GenerateSummary s = generate(request);
  const ReconstructSummary& r = s.reconstruction;
  std::printf("mesh: %zu vertices, %zu faces, %s -> %s\n", r.mesh.vertex_count(), r.mesh.face_count(),
              r.topology.summary().c_str(), request.output.string().c_str());
  std::printf("stages (%s):\n", nn::precision_name(s.precision));
  for (const GenerateStageReport& stage : s.stages) {
    if (stage.resumed)
      std::printf("  %-12s from the intermediates\n", stage.name.c_str());
    else
      std::printf("  %-12s %8.1f s   peak memory %6.0f MiB\n", stage.name.c_str(), stage.seconds,
                  stage.peak_memory_mib);
  }
  std::printf("  %-12s %8.1f s\n", "total", s.total_seconds());
  print_texture_summary(request.reconstruct, r);
  if (!a.json_path.empty())
    write_atomically(a.json_path, [&](const std::filesystem::path& tmp) {
      std::ofstream f(tmp);
      f << summary_json(s).dump(2) << "\n";
      f.close();
      require(bool(f), "cannot write " + a.json_path);
    });
}

const CommandRegistration registration{
    "generate", "One photo to a textured 3D mesh: the whole Unique3D method", [](CLI::App& sub) {
      auto a = std::make_shared<GenerateArgs>();
      GenerateRequest& r = a->request;
      sub.add_option("image", r.image,
                     "The photo (PNG or JPEG); best with the object on a transparent background, facing the camera. "
                     "Not needed with --from-intermediates, whose front.png is the photo");
      sub.add_option("-o,--output", r.output, "Output mesh (.glb, .obj or .ply)")->required();
      add_network_options(sub, a->network);
      add_raw_matte_flag(sub, r.raw_matte);
      sub.add_flag("--no-refine", a->no_refine,
                   "Skip the ControlNet-tile refinement of the four views (resize them to the size it would give, "
                   "half of --refine-size, instead; the stable-diffusion-v1-5, controlnet-tile and IP-Adapter "
                   "folders are then not needed)");
      sub.add_option("--steps", a->steps, "Denoising steps of the multi-view and normal models (default: 30 each)")
          ->check(CLI::Range(1, 1000));
      sub.add_option("--keep-intermediates", r.keep_intermediates,
                     "Write every stage's outputs to this folder (docs/generate.md lists them)");
      sub.add_option("--from-intermediates", r.from_intermediates,
                     "Resume from a folder written by --keep-intermediates, after its last complete stage");
      sub.add_flag("--official-scale", r.official_output_scale,
                   "Scale the output by 0.675 like the official release (default: the views' frame, unscaled)");
      sub.add_option("--json", a->json_path, "Also write the summary (stages, times, memory, files) to this JSON file");
      sub.add_option("--multiview-size", r.multiview.size,
                     "Side of the four views the multi-view model draws; it was trained at this default, and "
                     "smaller is faster and worse")
          ->capture_default_str()
          ->check(CLI::Range(16, 4096));
      sub.add_option("--refine-size", r.refine_options.size,
                     "Side of the 2x2 grid of views the refinement redraws (each view comes back at half of it)")
          ->capture_default_str()
          ->check(CLI::Range(32, 8192));
      sub.add_option("--normal-size", r.normals.size,
                     "Side of the normal model's input and output; it was trained at this default, and smaller "
                     "is faster and worse")
          ->capture_default_str()
          ->check(CLI::Range(16, 4096));
      add_isomer_step_options(sub, a->isomer);
      add_mesh_output_options(sub, a->output, r.reconstruct);
      return [a] { run(*a); };
    }};

}  // namespace
}  // namespace u3d::cli
