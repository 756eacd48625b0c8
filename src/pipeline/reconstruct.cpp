#include "pipeline/reconstruct.h"

#include <cctype>
#include <optional>

#include "core/error.h"
#include "core/view_set.h"
#include "io/mesh_io.h"
#include "isomer/silhouette_check.h"
#include "render/preview.h"

namespace u3d {
namespace {

std::string lower_extension(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::filesystem::path with_suffix(const std::filesystem::path& output, const std::string& suffix) {
  return output.parent_path() / (output.stem().string() + suffix);
}

void check_request_output(const ReconstructRequest& request) {
  if (request.output.empty())
    require(!request.previews, "previews need an output mesh file (they are written beside it)");
  else
    check_mesh_output(request.output);
}

}  // namespace

double ReconstructSummary::total_seconds() const {
  double total = 0.0;
  for (const StageTiming& t : timings) total += t.seconds;
  return total;
}

void check_mesh_output(const std::filesystem::path& out) {
  const std::string ext = lower_extension(out);
  require(ext == ".glb" || ext == ".obj" || ext == ".ply",
          "output " + out.string() + ": unsupported extension (use .glb, .obj or .ply)");
  const std::filesystem::path out_dir = out.parent_path().empty() ? "." : out.parent_path();
  require(std::filesystem::is_directory(out_dir), "output folder " + out_dir.string() + " does not exist");
}

ReconstructSummary reconstruct_folder(const ReconstructRequest& request, ProgressListener* listener) {
  std::optional<ProgressScope> scope;
  if (listener) scope.emplace(listener);
  check_request_output(request);
  StageTimer load_timer("loading views");
  const ViewSet views = load_view_set(request.views_dir, request.normal_space);
  const double load_seconds = load_timer.finish();
  ReconstructSummary summary = reconstruct_view_set(views, request);
  summary.timings.insert(summary.timings.begin(), {"load", load_seconds});
  return summary;
}

ReconstructSummary reconstruct_view_set(const ViewSet& views, const ReconstructRequest& request,
                                        ProgressListener* listener) {
  std::optional<ProgressScope> scope;
  if (listener) scope.emplace(listener);
  const std::filesystem::path& out = request.output;
  check_request_output(request);
  ReconstructSummary summary;
  ReconstructResult result = reconstruct(views, request.options);
  summary.timings.insert(summary.timings.end(), result.timings.begin(), result.timings.end());
  summary.mesh = std::move(result.mesh);
  summary.coloring = result.coloring;
  summary.texture = result.texture;
  summary.topology = surface_topology(summary.mesh);
  summary.silhouette_iou = silhouette_iou(summary.mesh, views);

  // Previews are rendered before anything is written, so a failure leaves no partial set of outputs.
  std::optional<std::array<Image, 2>> previews;
  double preview_seconds = 0.0;
  if (request.previews) {
    StageTimer preview_timer("rendering previews");
    previews = std::array<Image, 2>{preview_four_views(summary.mesh), preview_turntable(summary.mesh)};
    preview_seconds = preview_timer.finish();
  }

  if (out.empty()) return summary;
  StageTimer write_timer("writing " + out.string());
  if (request.official_output_scale) {
    Mesh scaled = summary.mesh;
    for (Vec3f& p : scaled.positions) p *= kOfficialOutputScale;
    write_mesh(scaled, out, {request.texture_format});
  } else {
    write_mesh(summary.mesh, out, {request.texture_format});
  }
  summary.written.push_back(out);
  if (previews) {
    const std::array<std::filesystem::path, 2> paths = {with_suffix(out, "_views.png"),
                                                        with_suffix(out, "_turntable.png")};
    for (size_t i = 0; i < paths.size(); ++i) {
      save_image((*previews)[i], paths[i]);
      summary.written.push_back(paths[i]);
    }
  }
  summary.timings.push_back({"write", write_timer.finish()});
  if (request.previews) summary.timings.push_back({"previews", preview_seconds});
  return summary;
}

}  // namespace u3d
