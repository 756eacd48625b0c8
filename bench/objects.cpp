// Object benchmark driver (not a Google Benchmark): for every object under the objects folder, render
// its four views with `unique3d render`, reconstruct them with `unique3d reconstruct` in each ablation
// (visual hull baseline, init only, ExplicitTarget everywhere or where views disagree, full), evaluate with `unique3d eval`, and
// write a Markdown and a JSON table (per object and mean). Stages the CLI cannot run yet (a missing subcommand or flag) are
// skipped and named in the table, never faked. Usage: bench_objects --help.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <sys/wait.h>

#include "core/atomic_file.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct Variant {
  std::string name;   // row label
  std::string flags;  // extra reconstruct flags; the first word must appear in `reconstruct --help`
};

// The ablations of the paper's Table 2, by reconstruct flag, after the mask-only visual hull baseline;
// then the full method without the silhouette fit, and writing vertex colours instead of the default texture.
const std::vector<Variant> kVariants = {
    {"visual hull", "--visual-hull"},
    {"init only", "--init-only"},
    {"ExplicitTarget everywhere", "--refine-target explicit"},
    {"ExplicitTarget where views disagree", "--refine-target disagree"},
    {"full", ""},  // the multi-view loss; 40k faces, a 2048 texture baked from the views
    {"no silhouette fit", "--no-silhouette-fit"},  // the full method without the silhouette fit (issue 14)
    {"full, vertex colours", "--colour vertex"},  // the mesh as reconstructed (~160k faces)
};

std::string quote(const fs::path& p) { return "'" + p.string() + "'"; }

struct CommandResult {
  int status = -1;
  double seconds = 0;
  std::string output;
};

CommandResult run(const std::string& command, const fs::path& log) {
  auto start = std::chrono::steady_clock::now();
  int raw = std::system((command + " > " + quote(log) + " 2>&1").c_str());
  CommandResult r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  std::ifstream f(log);
  std::stringstream ss;
  ss << f.rdbuf();
  r.output = ss.str();
  return r;
}

std::string last_line(const std::string& text) {
  std::string s = text;
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  auto nl = s.rfind('\n');
  return nl == std::string::npos ? s : s.substr(nl + 1);
}

fs::path find_mesh(const fs::path& dir) {
  std::vector<fs::path> found;
  for (const auto& e : fs::directory_iterator(dir)) {
    std::string ext = e.path().extension().string();
    if (ext == ".obj" || ext == ".glb" || ext == ".gltf" || ext == ".ply") found.push_back(e.path());
  }
  std::sort(found.begin(), found.end());
  return found.empty() ? fs::path() : found.front();
}

void write_text(const fs::path& path, const std::string& text) {
  u3d::write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << text;
    f.close();
    if (!f) throw std::runtime_error("cannot write " + path.string());
  });
}

std::string fmt(double v, const char* spec) {
  char buf[64];
  std::snprintf(buf, sizeof buf, spec, v);
  return buf;
}

const std::vector<std::string> kMetricKeys = {"cd",   "iou",  "fscore",  "fscore_visible", "hidden",
                                              "psnr", "ssim", "input_psnr", "silhouette_iou_min", "spurious_px", "spurious_pct",
                                              "spurious_blob", "missing_blob", "components", "hull_components",
                                              "seconds", "faces", "mb"};

// The worst view of `unique3d eval --views` (the mask_agreement object of its JSON): the most spurious
// pixels, the largest share of the mask they make, the largest spurious and missing blobs; and the
// mesh's and the visual hull's pieces.
void add_mask_agreement(const json& m, json& row) {
  double pixels = 0, share = 0, blob = 0, missing = 0;
  for (const auto& v : m["views"]) {
    const double spurious = v["spurious"]["pixels"].get<double>();
    pixels = std::max(pixels, spurious);
    share = std::max(share, 100.0 * spurious / std::max(v["mask_pixels"].get<double>(), 1.0));
    blob = std::max(blob, v["spurious"]["largest_blob"].get<double>());
    missing = std::max(missing, v["missing"]["largest_blob"].get<double>());
  }
  row["spurious_px"] = pixels;
  row["spurious_pct"] = share;
  row["spurious_blob"] = blob;
  row["missing_blob"] = missing;
  row["components"] = m["mesh_components"];
  row["hull_components"] = m["hull_components"];
}

// The smallest of the four per-view silhouette IoUs `unique3d reconstruct` prints
// ("silhouette IoU: front F, right R, back B, left L"); negative when the line is missing.
double min_silhouette_iou(const std::string& output) {
  const std::string key = "silhouette IoU:";
  const size_t at = output.find(key);
  if (at == std::string::npos) return -1.0;
  std::istringstream line(output.substr(at + key.size(), output.find('\n', at) - at - key.size()));
  double lowest = 2.0;
  int found = 0;
  for (std::string word; line >> word;) {
    if (word.back() == ',') word.pop_back();
    char* end = nullptr;
    const double v = std::strtod(word.c_str(), &end);
    if (end != word.c_str() && *end == '\0') lowest = std::min(lowest, v), ++found;
  }
  return found == 4 ? lowest : -1.0;
}

std::string markdown(const json& rows, const json& means, const std::string& fscore_label) {
  std::string md = "| object | res | variant | CD-L1 | Vol. IoU | " + fscore_label + " | " + fscore_label +
                   " visible GT | hidden GT | PSNR | SSIM | input-view PSNR | min sil. IoU | spurious px | spurious % | spurious blob | "
                   "missing blob | pieces / hull | time (s) | faces | GLB (MB) | status |\n"
                   "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  auto cell = [](const json& row, const std::string& key, const char* spec) {
    return row.contains(key) && row[key].is_number() ? fmt(row[key].get<double>(), spec) : std::string("-");
  };
  auto line = [&](const json& r) {
    md += "| " + r["object"].get<std::string>() + " | " + std::to_string(r["resolution"].get<int>()) + " | " +
          r["variant"].get<std::string>() + " | " + cell(r, "cd", "%.5f") + " | " + cell(r, "iou", "%.4f") + " | " +
          cell(r, "fscore", "%.4f") + " | " + cell(r, "fscore_visible", "%.4f") + " | " + cell(r, "hidden", "%.3f") +
          " | " + cell(r, "psnr", "%.2f") + " | " + cell(r, "ssim", "%.4f") + " | " +
          cell(r, "input_psnr", "%.2f") + " | " + cell(r, "silhouette_iou_min", "%.4f") + " | " + cell(r, "spurious_px", "%.0f") + " | " +
          cell(r, "spurious_pct", "%.3f") + " | " + cell(r, "spurious_blob", "%.0f") + " | " +
          cell(r, "missing_blob", "%.0f") + " | " + cell(r, "components", "%.0f") + " / " +
          cell(r, "hull_components", "%.0f") + " | " + cell(r, "seconds", "%.1f") + " | " + cell(r, "faces", "%.0f") + " | " + cell(r, "mb", "%.2f") + " | " + r["status"].get<std::string>() + " |\n";
  };
  for (const auto& r : rows) line(r);
  for (const auto& r : means) line(r);
  return md;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Render, reconstruct and evaluate every object of a folder; writes results.md and results.json"};
  fs::path self = fs::absolute(argv[0]).parent_path();
  std::string objects_dir = (fs::path(UNIQUE3D_SOURCE_DIR) / ".." / "shared" / "data" / "objects").string();
  std::string out_dir = "bench_objects_out";
  std::string cli = (self.parent_path() / "unique3d").string();
  std::vector<int> resolutions = {512, 2048};
  std::vector<std::string> only;
  std::vector<std::string> only_variants;
  std::string perturb_args, eval_args, reconstruct_args;
  bool shared_frame = false;
  float fill = 0.9f;
  float fscore_threshold = 0.05f;
  app.add_option("--objects", objects_dir, "Folder of object folders (each with one mesh file)")->capture_default_str();
  app.add_option("--out", out_dir, "Output folder")->capture_default_str();
  app.add_option("--cli", cli, "unique3d binary")->capture_default_str();
  app.add_option("--res", resolutions, "View resolutions")->delimiter(',')->capture_default_str();
  app.add_option("--only", only, "Object names to run (default: all)")->delimiter(',');
  app.add_option("--variants", only_variants, "Variant names to run, separated by ';' (default: all), e.g. 'full;full, vertex colours'")
      ->delimiter(';');
  app.add_option("--perturb", perturb_args, "Arguments for `unique3d perturb` applied to the views before reconstruction");
  app.add_option("--reconstruct-args", reconstruct_args, "Extra arguments for every `unique3d reconstruct` row");
  app.add_option("--eval-args", eval_args, "Extra arguments for `unique3d eval` (e.g. '--iou-resolution 128')");
  app.add_flag("--shared-frame", shared_frame,
               "Evaluate in the views' frame (--given-frame --gt-render-fill) instead of normalizing each mesh");
  app.add_option("--fill", fill, "The --fill of `unique3d render` (for --shared-frame)")->capture_default_str();
  app.add_option("--fscore-threshold", fscore_threshold, "F-score threshold shown in the table")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  if (!fs::is_directory(objects_dir)) {
    std::printf("bench_objects: no objects folder at %s: nothing to do (skipped)\n", objects_dir.c_str());
    return 0;
  }
  if (!fs::exists(cli)) {
    std::fprintf(stderr, "bench_objects: unique3d binary not found at %s (use --cli)\n", cli.c_str());
    return 1;
  }
  u3d::ensure_directory(out_dir);
  const fs::path out = fs::absolute(out_dir);
  const std::string bin = quote(fs::absolute(cli)) + " --quiet";

  // Which stages and ablations this build of the CLI offers.
  // An unknown subcommand makes CLI11 print the top-level help, whose usage line lacks the name.
  auto help = [&](const std::string& sub) {
    CommandResult r = run(quote(fs::absolute(cli)) + " " + sub + " --help", out / "help.txt");
    if (r.output.find(" " + sub + " [OPTIONS]") == std::string::npos) r.status = -1;
    return r;
  };
  const CommandResult render_help = help("render"), reconstruct_help = help("reconstruct"), eval_help = help("eval");
  std::vector<std::string> notes;
  const bool can_render = render_help.status == 0, can_reconstruct = reconstruct_help.status == 0;
  if (!can_render) notes.push_back("`unique3d render` is not available in this build: nothing was reconstructed");
  if (!can_reconstruct) notes.push_back("`unique3d reconstruct` is not available in this build: rows are skipped");
  if (eval_help.status != 0) {
    std::fprintf(stderr, "bench_objects: %s has no eval subcommand\n", cli.c_str());
    return 1;
  }
  std::vector<Variant> variants;
  for (const auto& name : only_variants)
    if (std::none_of(kVariants.begin(), kVariants.end(), [&](const Variant& v) { return v.name == name; })) {
      std::fprintf(stderr, "bench_objects: unknown variant '%s'\n", name.c_str());
      return 1;
    }
  for (const auto& v : kVariants) {
    if (!only_variants.empty() && std::find(only_variants.begin(), only_variants.end(), v.name) == only_variants.end())
      continue;
    std::string flag = v.flags.substr(0, v.flags.find(' '));
    if (flag.empty() || reconstruct_help.output.find(flag) != std::string::npos) variants.push_back(v);
    else if (can_reconstruct) notes.push_back("ablation '" + v.name + "' skipped: reconstruct has no " + flag + " flag yet");
  }

  std::vector<fs::path> objects;
  for (const auto& e : fs::directory_iterator(objects_dir))
    if (e.is_directory() && (only.empty() || std::find(only.begin(), only.end(), e.path().filename()) != only.end()))
      objects.push_back(e.path());
  std::sort(objects.begin(), objects.end());

  json rows = json::array();
  for (const auto& obj : objects) {
    const std::string name = obj.filename().string();
    const fs::path mesh = find_mesh(obj);
    if (mesh.empty()) {
      notes.push_back(name + ": no mesh file, skipped");
      continue;
    }
    for (int res : resolutions) {
      const fs::path dir = out / name / std::to_string(res);
      u3d::ensure_directory(dir);
      auto row_base = [&](const std::string& variant) {
        return json{{"object", name}, {"resolution", res}, {"variant", variant}};
      };
      if (!can_render) break;
      std::printf("[bench] %s @ %d: render\n", name.c_str(), res);
      std::fflush(stdout);
      CommandResult r = run(bin + " render " + quote(mesh) + " -o " + quote(dir / "views") + " --res " +
                                std::to_string(res) + " --fill " + fmt(fill, "%g"),
                            dir / "render.log");
      if (r.status != 0) {
        json row = row_base("-");
        row["status"] = "render failed: " + last_line(r.output);
        rows.push_back(row);
        continue;
      }
      fs::path views = dir / "views";
      if (!perturb_args.empty()) {
        r = run(bin + " perturb " + quote(views) + " -o " + quote(dir / "views_perturbed") + " " + perturb_args,
                dir / "perturb.log");
        if (r.status != 0) {
          json row = row_base("-");
          row["status"] = "perturb failed: " + last_line(r.output);
          rows.push_back(row);
          continue;
        }
        views = dir / "views_perturbed";
      }
      for (const auto& v : variants) {
        json row = row_base(v.name);
        if (!can_reconstruct) {
          row["status"] = "skipped: no reconstruct";
          rows.push_back(row);
          continue;
        }
        std::string tag = v.name;
        for (auto& c : tag)
          if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
        const fs::path recon = dir / (tag + ".glb"), metrics = dir / (tag + "_eval.json");
        std::printf("[bench] %s @ %d: reconstruct (%s)\n", name.c_str(), res, v.name.c_str());
        std::fflush(stdout);
        r = run(bin + " reconstruct " + quote(views) + " -o " + quote(recon) + " " + v.flags + " " + reconstruct_args, dir / (tag + "_reconstruct.log"));
        row["seconds"] = r.seconds;
        const double silhouette = min_silhouette_iou(r.output);
        if (silhouette >= 0.0) row["silhouette_iou_min"] = silhouette;
        if (r.status != 0) {
          row["status"] = "reconstruct failed: " + last_line(r.output);
          rows.push_back(row);
          continue;
        }
        std::string frame = shared_frame ? " --given-frame --gt-render-fill " + fmt(fill, "%g") : "";
        r = run(bin + " eval " + quote(recon) + " " + quote(mesh) + frame + " --fscore-thresholds " +
                    fmt(fscore_threshold, "%g") + " --views " + quote(views) + " --json " + quote(metrics) + " " + eval_args,
                dir / (tag + "_eval.log"));
        if (r.status != 0) {
          row["status"] = "eval failed: " + last_line(r.output);
          rows.push_back(row);
          continue;
        }
        std::ifstream f(metrics);
        json m = json::parse(f);
        row["cd"] = m["chamfer"]["l1"];
        row["iou"] = m["volume_iou"]["iou"];
        row["fscore"] = m["fscore"][0]["fscore"];
        row["fscore_visible"] = m["visible_gt"]["fscore"][0]["fscore"];
        row["hidden"] = m["visible_gt"]["hidden_samples"].get<double>() / m["chamfer"]["samples_per_mesh"].get<double>();
        if (m["appearance"].is_object()) {
          row["psnr"] = m["appearance"]["psnr"];
          row["ssim"] = m["appearance"]["ssim"];
        }
        if (m["input_view_psnr"].is_object()) row["input_psnr"] = m["input_view_psnr"]["psnr"];
        add_mask_agreement(m["mask_agreement"], row);
        row["faces"] = m["pred"]["faces"];
        row["mb"] = double(fs::file_size(recon)) / 1e6;
        row["warnings"] = m["warnings"];
        row["status"] = "ok";
        rows.push_back(row);
      }
    }
  }

  // Means per (resolution, variant) over the objects that finished.
  std::map<std::pair<int, std::string>, std::vector<json>> groups;
  for (const auto& r : rows)
    if (r["status"] == "ok") groups[{r["resolution"].get<int>(), r["variant"].get<std::string>()}].push_back(r);
  json means = json::array();
  for (const auto& [key, members] : groups) {
    json mean = {{"object", "mean (" + std::to_string(members.size()) + ")"}, {"resolution", key.first}, {"variant", key.second},
                 {"status", "ok"}};
    for (const auto& k : kMetricKeys) {
      double sum = 0;
      size_t n = 0;
      for (const auto& m : members)
        if (m.contains(k) && m[k].is_number()) sum += m[k].get<double>(), ++n;
      if (n > 0) mean[k] = sum / double(n);
    }
    means.push_back(mean);
  }

  const std::string fscore_label = "F@" + fmt(fscore_threshold, "%g");
  json doc = {{"objects_dir", objects_dir},
              {"frame", shared_frame ? "shared (views' frame)" : "normalized"},
              {"fscore_threshold", fscore_threshold},
              {"perturb", perturb_args},
              {"rows", rows},
              {"means", means},
              {"notes", notes}};
  std::string md = "# Object benchmark\n\nFrame: " + doc["frame"].get<std::string>() + "; CD-L1, IoU, " + fscore_label +
                   " (also over the GT surface visible from outside; hidden GT = share of GT samples no outside view sees), "
                   "PSNR, SSIM and the input-view PSNR (the mesh rendered in each input view, over its mask) as defined in "
                   "docs/evaluation.md; min sil. IoU = the smallest of the four silhouette IoUs against "
                   "the input masks that `unique3d reconstruct` prints; spurious px / % / blob = in the worst view, the mesh pixels "
                   "farther than 2 px from the input mask, their share of the mask's area and the largest connected group of "
                   "them; missing blob = the largest group of mask pixels farther than 2 px from the mesh; pieces / hull = "
                   "connected pieces of the mesh and of the masks' visual hull (docs/evaluation.md); time = wall time of "
                   "`unique3d reconstruct`.\n";
  if (!perturb_args.empty()) md += "Views perturbed with `unique3d perturb " + perturb_args + "`.\n";
  md += "\n" + markdown(rows, means, fscore_label);
  if (!notes.empty()) {
    md += "\nNotes:\n";
    for (const auto& n : notes) md += "- " + n + "\n";
  }
  write_text(out / "results.json", doc.dump(2) + "\n");
  write_text(out / "results.md", md);
  std::fputs(md.c_str(), stdout);
  return 0;
}
