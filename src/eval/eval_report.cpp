#include "eval/eval_report.h"

#include <cstdio>

#include "eval/image_metrics.h"

namespace u3d {

namespace {

nlohmann::json mesh_json(const MeshSummary& m) {
  return {{"vertices", m.vertices},
          {"faces", m.faces},
          {"has_color", m.has_color},
          {"closed", m.diagnostics.closed()},
          {"boundary_edges", m.diagnostics.boundary_edges},
          {"nonmanifold_edges", m.diagnostics.nonmanifold_edges},
          {"degenerate_faces", m.diagnostics.degenerate_faces}};
}

nlohmann::json fscores_json(const std::vector<FScore>& fscores) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& f : fscores)
    out.push_back({{"threshold", f.threshold}, {"precision", f.precision}, {"recall", f.recall}, {"fscore", f.fscore}});
  return out;
}

nlohmann::json blobs_json(const PixelBlobs& b) {
  return {{"pixels", b.pixels}, {"blobs", b.blobs}, {"largest_blob", b.largest_blob}};
}

nlohmann::json mask_agreement_json(const MaskAgreement& m) {
  nlohmann::json views = nlohmann::json::array();
  for (View v : kAllViews) {
    const ViewMaskAgreement& a = m.views[size_t(v)];
    views.push_back({{"view", view_name(v)},
                     {"mask_pixels", a.mask_pixels},
                     {"mesh_pixels", a.mesh_pixels},
                     {"spurious", blobs_json(a.spurious)},
                     {"missing", blobs_json(a.missing)}});
  }
  return {{"tolerance_px", m.options.tolerance_px},
          {"hull_resolution", m.options.hull_resolution},
          {"mesh_components", m.mesh_components},
          {"hull_components", m.hull_components},
          {"views", views}};
}

nlohmann::json input_view_psnr_json(const InputViewPsnr& p) {
  nlohmann::json views = nlohmann::json::array();
  for (View v : kAllViews)
    views.push_back({{"view", view_name(v)}, {"psnr", p.views[size_t(v)]}, {"pixels", p.pixels[size_t(v)]}});
  return {{"psnr", p.mean}, {"ssaa", p.ssaa}, {"views", views}};
}

std::string format(const char* fmt, double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, value);
  return buf;
}

}  // namespace

nlohmann::json report_to_json(const EvalReport& r) {
  nlohmann::json j;
  j["frame"] = r.options.normalize ? "normalized" : "shared";
  j["gt_render_fill"] = r.options.gt_render_fill;
  j["pred"] = mesh_json(r.pred);
  j["gt"] = mesh_json(r.gt);
  j["chamfer"] = {{"l1", r.chamfer.chamfer_l1},
                  {"l2", r.chamfer.chamfer_l2},
                  {"accuracy", r.chamfer.accuracy},
                  {"completeness", r.chamfer.completeness},
                  {"samples_per_mesh", r.options.surface_samples},
                  {"seed", r.options.seed}};
  j["fscore"] = fscores_json(r.fscores);
  j["visible_gt"] = {{"hidden_samples", r.gt_hidden_samples},
                     {"directions", r.options.visibility.directions},
                     {"resolution", r.options.visibility.resolution},
                     {"chamfer", {{"l1", r.chamfer_visible.chamfer_l1},
                                  {"l2", r.chamfer_visible.chamfer_l2},
                                  {"completeness", r.chamfer_visible.completeness}}},
                     {"fscore", fscores_json(r.fscores_visible)}};
  j["volume_iou"] = {{"iou", r.iou.iou},
                     {"resolution", r.iou.resolution},
                     {"pred_cells", r.iou.pred_cells},
                     {"gt_cells", r.iou.gt_cells},
                     {"intersection_cells", r.iou.intersection_cells},
                     {"union_cells", r.iou.union_cells}};
  if (r.appearance) {
    const auto& a = *r.appearance;
    nlohmann::json views = nlohmann::json::array();
    for (const auto& v : a.views)
      views.push_back({{"azimuth_deg", v.view.azimuth_deg},
                       {"elevation_deg", v.view.elevation_deg},
                       {"psnr", v.psnr},
                       {"ssim", v.ssim}});
    j["appearance"] = {{"psnr", a.psnr},
                       {"ssim", a.ssim},
                       {"psnr_cap_db", kPsnrCapDb},
                       {"resolution", r.options.appearance_options.resolution},
                       {"ssaa", r.options.appearance_options.ssaa},
                       {"half_extent", a.half_extent},
                       {"views", views}};
  } else {
    j["appearance"] = nullptr;
  }
  j["mask_agreement"] = r.mask_agreement ? mask_agreement_json(*r.mask_agreement) : nlohmann::json(nullptr);
  j["input_view_psnr"] = r.input_view_psnr ? input_view_psnr_json(*r.input_view_psnr) : nlohmann::json(nullptr);
  j["warnings"] = r.warnings;
  j["seconds"] = {{"geometry", r.geometry_seconds}, {"appearance", r.appearance_seconds}};
  return j;
}

std::string report_summary(const EvalReport& r) {
  std::string s;
  std::string frame = r.options.normalize ? "each mesh normalized to [-0.5, 0.5]"
                                          : "shared (the GT's normalization to [-0.5, 0.5] applied to both)";
  if (r.options.gt_render_fill > 0) frame += ", GT first placed as rendered with fill " + format("%g", r.options.gt_render_fill);
  s += "frame:          " + frame + "\n";
  s += "faces:          pred " + std::to_string(r.pred.faces) + ", gt " + std::to_string(r.gt.faces) + "\n";
  s += "Chamfer-L1:     " + format("%.6f", r.chamfer.chamfer_l1) + "  (accuracy " +
       format("%.6f", r.chamfer.accuracy) + ", completeness " + format("%.6f", r.chamfer.completeness) + ")\n";
  s += "Chamfer-L2:     " + format("%.3e", r.chamfer.chamfer_l2) + "\n";
  for (const auto& f : r.fscores)
    s += "F-score@" + format("%-7g", f.threshold) + format("%.4f", f.fscore) + "  (precision " +
         format("%.4f", f.precision) + ", recall " + format("%.4f", f.recall) + ")\n";
  s += "visible GT:     " + std::to_string(r.gt_hidden_samples) + " of " + std::to_string(r.options.surface_samples) +
       " GT samples hidden from all " + std::to_string(r.options.visibility.directions) +
       " outside views; without them Chamfer-L1 " + format("%.6f", r.chamfer_visible.chamfer_l1) + " (completeness " +
       format("%.6f", r.chamfer_visible.completeness) + ")\n";
  for (const auto& f : r.fscores_visible)
    s += "  F-score@" + format("%-5g", f.threshold) + format("%.4f", f.fscore) + "  (recall " + format("%.4f", f.recall) +
         ")\n";
  s += "volume IoU:     " + format("%.4f", r.iou.iou) + "  (" + std::to_string(r.iou.resolution) + "^3 grid)\n";
  if (r.appearance) {
    s += "PSNR:           " + format("%.3f", r.appearance->psnr) + " dB  (mean of 24 views)\n";
    s += "SSIM:           " + format("%.4f", r.appearance->ssim) + "\n";
  }
  if (r.input_view_psnr) {
    const InputViewPsnr& p = *r.input_view_psnr;
    s += "input views:    PSNR " + format("%.3f", p.mean) + " dB where mesh and mask meet (mean of 4;";
    for (View v : kAllViews) s += std::string(" ") + view_name(v) + " " + format("%.2f", p.views[size_t(v)]);
    s += ")\n";
  }
  if (r.mask_agreement) {
    const MaskAgreement& m = *r.mask_agreement;
    auto per_view = [&](const char* what, PixelBlobs ViewMaskAgreement::*kind) {
      std::string line = std::string(what) + " (farther than " + format("%g", m.options.tolerance_px) + " px):";
      for (View v : kAllViews) {
        const PixelBlobs& b = m.views[size_t(v)].*kind;
        line += std::string(v == View::Front ? " " : ", ") + view_name(v) + " " + std::to_string(b.pixels) + " px";
        if (b.pixels) line += " in " + std::to_string(b.blobs) + " blob(s), largest " + std::to_string(b.largest_blob);
      }
      return line + "\n";
    };
    s += "input masks:    " + per_view("mesh over background", &ViewMaskAgreement::spurious);
    s += "                " + per_view("mask not covered", &ViewMaskAgreement::missing);
    s += "components:     mesh " + std::to_string(m.mesh_components) + ", visual hull of the masks " +
         std::to_string(m.hull_components) + "\n";
  }
  for (const auto& w : r.warnings) s += "warning: " + w + "\n";
  return s;
}

}  // namespace u3d
