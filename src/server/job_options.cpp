#include "server/job_options.h"

#include <charconv>
#include <set>

#include "core/error.h"
#include "server/job_runner.h"

namespace u3d::server {
namespace {

namespace fs = std::filesystem;

template <typename T>
T parse_number(const std::string& field, const std::string& text, T lo, T hi) {
  T value{};
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  require(ec == std::errc() && ptr == end && !text.empty() && value >= lo && value <= hi,
          "option " + field + ": '" + text + "' is not a whole number in [" + std::to_string(lo) + ", " +
              std::to_string(hi) + "]");
  return value;
}

std::string parse_choice(const std::string& field, const std::string& text, const std::set<std::string>& choices) {
  if (choices.count(text)) return text;
  std::string list;
  for (const std::string& c : choices) list += (list.empty() ? "" : ", ") + c;
  throw Error("option " + field + ": '" + text + "' is not one of " + list);
}

// The options both kinds share: the output mesh's faces and colour.
void apply_mesh_options(const std::map<std::string, std::string>& fields, ReconstructOptions& o,
                        nlohmann::json& echo) {
  if (auto it = fields.find("faces"); it != fields.end()) echo["faces"] = o.faces = parse_number(it->first, it->second, size_t(100), size_t(2000000));
  if (auto it = fields.find("colour"); it != fields.end()) {
    echo["colour"] = parse_choice(it->first, it->second, {"texture", "vertex"});
    o.color_mode = it->second == "texture" ? ColorMode::Texture : ColorMode::Vertex;
  }
  if (auto it = fields.find("texture_size"); it != fields.end()) {
    require(o.color_mode == ColorMode::Texture, "option texture_size needs colour=texture");
    echo["texture_size"] = o.texture.atlas.texture_size = parse_number(it->first, it->second, 64, 8192);
  }
}

}  // namespace

JobSpec make_job_spec(JobKind kind, const std::map<std::string, std::string>& fields, const fs::path& folder,
                      const fs::path& models) {
  const std::set<std::string> shared = {"faces", "colour", "texture_size"};
  const std::set<std::string> own = kind == JobKind::Reconstruct
                                        ? std::set<std::string>{"coarse_steps", "refine_steps"}
                                        : std::set<std::string>{"seed", "steps", "dtype", "refine", "raw_matte"};
  for (const auto& [field, value] : fields)
    if (!shared.count(field) && !own.count(field)) {
      std::string known;
      for (const auto* names : {&shared, &own})
        for (const std::string& n : *names) known += (known.empty() ? "" : ", ") + n;
      throw Error("unknown option '" + field + "' for a " + job_kind_name(kind) + " job (options: " + known + ")");
    }

  JobSpec spec;
  spec.kind = kind;
  spec.options = nlohmann::json::object();
  if (kind == JobKind::Reconstruct) {
    ReconstructRequest& r = spec.reconstruct;
    r.views_dir = job_input_dir(folder);
    r.output = job_mesh_path(folder);
    r.previews = true;
    apply_mesh_options(fields, r.options, spec.options);
    if (auto it = fields.find("coarse_steps"); it != fields.end())
      spec.options["coarse_steps"] = r.options.coarse.steps = parse_number(it->first, it->second, 0, 2000);
    if (auto it = fields.find("refine_steps"); it != fields.end())
      spec.options["refine_steps"] = r.options.refine.steps = parse_number(it->first, it->second, 0, 2000);
    return spec;
  }

  GenerateRequest& g = spec.generate;
  g.output = job_mesh_path(folder);
  g.keep_intermediates = job_intermediates_dir(folder);
  g.network.models = models;
  apply_mesh_options(fields, g.reconstruct, spec.options);
  if (auto it = fields.find("seed"); it != fields.end())
    spec.options["seed"] = g.network.seed = parse_number(it->first, it->second, uint64_t(0), UINT64_MAX);
  if (auto it = fields.find("steps"); it != fields.end())
    spec.options["steps"] = g.multiview.steps = g.normals.steps = parse_number(it->first, it->second, 1, 200);
  if (auto it = fields.find("dtype"); it != fields.end()) {
    spec.options["dtype"] = parse_choice(it->first, it->second, {"auto", "fp32", "bf16"});
    if (it->second != "auto") g.network.precision = nn::parse_precision(it->second, "option dtype");
  }
  if (auto it = fields.find("refine"); it != fields.end())
    spec.options["refine"] = g.refine = parse_choice(it->first, it->second, {"true", "false"}) == "true";
  if (auto it = fields.find("raw_matte"); it != fields.end())
    spec.options["raw_matte"] = g.raw_matte = parse_choice(it->first, it->second, {"true", "false"}) == "true";
  return spec;
}

}  // namespace u3d::server
