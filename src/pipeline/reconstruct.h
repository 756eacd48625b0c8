#pragma once
// The library's facade for ISOMER: a view-set folder in, a mesh file (and previews) out, with the
// reports `unique3d reconstruct` prints. The CLI only turns options into a ReconstructRequest and prints
// the summary; a web page or a Python binding calls the same function with its own ProgressListener.
#include <array>
#include <filesystem>
#include <vector>

#include "core/camera.h"
#include "core/mesh.h"
#include "core/progress.h"
#include "core/view_set.h"
#include "geometry/mesh_topology.h"
#include "io/image_codec.h"
#include "isomer/reconstruct.h"

namespace u3d {

// The official app writes 0.675 * p (conventions.md 2.0: scale 1.35 / 2, no rotation).
inline constexpr float kOfficialOutputScale = 0.675f;

struct ReconstructRequest {
  std::filesystem::path views_dir;  // front/right/back/left _rgb.png and _normal.png (core/view_set.h)
  NormalSpace normal_space = NormalSpace::World;
  std::filesystem::path output;        // .glb, .obj or .ply; empty: nothing is written (the summary holds the mesh)
  bool previews = false;               // also <stem>_views.png (the four views) and <stem>_turntable.png; needs output
  bool official_output_scale = false;  // write the mesh scaled by kOfficialOutputScale
  TextureFormat texture_format = TextureFormat::Png;  // of the baked texture (options.color_mode Texture)
  ReconstructOptions options;
};

struct ReconstructSummary {
  Mesh mesh;              // as reconstructed, in the views' frame (the file may be scaled)
  MeshTopology topology;  // of the surface (UV seams are not borders)
  ColoringReport coloring;
  TextureBakeReport texture;              // with ColorMode::Texture
  std::array<float, 4> silhouette_iou{};  // per view, against the input masks
  std::vector<StageTiming> timings;       // "load", ISOMER's stages, "write", "previews" (if written)
  std::vector<std::filesystem::path> written;
  double total_seconds() const;
};

// Checks the request and the view set before any work (Error naming the file or value), reconstructs,
// and writes the outputs (if any) only after everything else succeeded (each atomically). Progress and
// cancellation go through `listener` (none: the thread's current one).
ReconstructSummary reconstruct_folder(const ReconstructRequest& request, ProgressListener* listener = nullptr);

// The same from a view set already loaded (request.views_dir is not read).
ReconstructSummary reconstruct_view_set(const ViewSet& views, const ReconstructRequest& request,
                                        ProgressListener* listener = nullptr);

// An Error when `output` cannot be a mesh file: an extension other than .glb, .obj, .ply, or a folder
// that does not exist.
void check_mesh_output(const std::filesystem::path& output);

}  // namespace u3d
