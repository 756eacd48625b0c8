// `unique3d render MESH -o DIR`: reference renders of a mesh in the four canonical views (colour and
// normal images), plus optional turntable previews.
#include <cstdio>
#include <string>

#include "cli/command.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "io/mesh_io.h"
#include "render/render_view.h"

namespace u3d::cli {

namespace {

struct RenderOptions {
  std::string mesh_path;
  std::string out_dir;
  int resolution = 512;
  int ssaa = 2;
  std::string normal_space = "world";
  bool flat = false;
  int turntable = 0;
  float elevation = 20.f;
  float fill = 0.9f;
  bool no_normalize = false;
};

void run_render(const RenderOptions& o) {
  namespace fs = std::filesystem;
  require(o.resolution * o.ssaa <= 8192,
          "--res x --ssaa must not exceed 8192 (got " + std::to_string(o.resolution * o.ssaa) + ")");
  Mesh mesh;
  {
    StageTimer t("loading " + o.mesh_path);
    mesh = read_mesh(o.mesh_path);
  }
  progress(std::to_string(mesh.vertex_count()) + " vertices, " + std::to_string(mesh.face_count()) + " faces");
  if (!o.no_normalize) normalize_to_unit_box(mesh, o.fill);
  const fs::path out(o.out_dir);

  RenderSettings settings;
  settings.normal_space = o.normal_space == "camera" ? NormalSpace::Camera : NormalSpace::World;
  settings.smooth_normals = !o.flat;
  settings.ssaa = o.ssaa;
  write_folder_atomically(out, [&](const fs::path& dir) {
    {
      StageTimer t("rendering 4 views at " + std::to_string(o.resolution) + " px");
      for (View v : kAllViews) {
        RenderedView r = render_view(mesh, view_camera(v, o.resolution), settings);
        save_image(r.rgb, dir / (std::string(view_name(v)) + "_rgb.png"));
        save_image(r.normal, dir / (std::string(view_name(v)) + "_normal.png"));
      }
    }
    if (o.turntable > 0) {
      StageTimer t("rendering " + std::to_string(o.turntable) + " turntable images");
      for (int i = 0; i < o.turntable; ++i) {
        const float azimuth = 360.f * float(i) / float(o.turntable);
        Camera cam = orthographic_camera(orbit_direction(azimuth, o.elevation), o.resolution, o.resolution);
        RenderedView r = render_view(mesh, cam, settings);
        char name[32];
        std::snprintf(name, sizeof name, "turntable_%03d.png", i);
        save_image(r.rgb, dir / name);
      }
    }
  });
  progress("wrote renders to " + out.string());
}

const CommandRegistration registration{
    "render", "Render a mesh: colour and normal images of the front/right/back/left views, optional turntable",
    [](CLI::App& sub) -> CommandAction {
      auto o = std::make_shared<RenderOptions>();
      sub.add_option("mesh", o->mesh_path, "Mesh file (.obj, .ply, .glb, .gltf)")->required();
      sub.add_option("-o,--output", o->out_dir, "Output folder (created if missing)")->required();
      sub.add_option("--res", o->resolution, "Image resolution in pixels")->check(CLI::Range(1, 8192))->capture_default_str();
      sub.add_option("--ssaa", o->ssaa, "Supersampling factor per axis for anti-aliasing (1 = off)")
          ->check(CLI::Range(1, 8))
          ->capture_default_str();
      sub.add_option("--normal-space", o->normal_space, "Normal map space")
          ->check(CLI::IsMember({"world", "camera"}))
          ->capture_default_str();
      sub.add_flag("--flat", o->flat, "Face normals instead of interpolated vertex normals");
      sub.add_option("--turntable", o->turntable, "Also write N colour previews around the object (turntable_000.png ...)")
          ->check(CLI::Range(0, 3600));
      sub.add_option("--elevation", o->elevation, "Camera elevation of the turntable in degrees")
          ->check(number_in(-90, 90))
          ->capture_default_str();
      sub.add_option("--fill", o->fill, "Scale so the longest bounding-box side spans [-fill, fill]")
          ->check(number_in(0.01, 1))
          ->capture_default_str();
      sub.add_flag("--no-normalize", o->no_normalize, "Render the mesh in its own coordinates (views cover [-1, 1]^2)");
      return [o] { run_render(*o); };
    }};

}  // namespace

}  // namespace u3d::cli
