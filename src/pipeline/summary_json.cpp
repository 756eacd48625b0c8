#include "pipeline/summary_json.h"

namespace u3d {
namespace {

nlohmann::json mesh_json(const ReconstructSummary& s) {
  return {{"vertices", s.mesh.vertex_count()},
          {"faces", s.mesh.face_count()},
          {"components", s.topology.components},
          {"watertight", s.topology.watertight},
          {"topology", s.topology.summary()},
          {"silhouette_iou", s.silhouette_iou}};
}

nlohmann::json written_json(const std::vector<std::filesystem::path>& written) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& path : written) j.push_back(path.string());
  return j;
}

}  // namespace

nlohmann::json summary_json(const ReconstructSummary& s) {
  nlohmann::json j;
  j["mesh"] = mesh_json(s);
  j["colouring"] = {
      {"confident", s.coloring.confident}, {"completed", s.coloring.completed}, {"unreachable", s.coloring.unreachable}};
  if (s.texture.charts > 0)
    j["texture"] = {{"charts", s.texture.charts}, {"texel_efficiency", s.texture.texel_efficiency}};
  j["timings"] = nlohmann::json::array();
  for (const StageTiming& t : s.timings) j["timings"].push_back({{"name", t.name}, {"seconds", t.seconds}});
  j["total_seconds"] = s.total_seconds();
  j["written"] = written_json(s.written);
  return j;
}

nlohmann::json summary_json(const GenerateSummary& s) {
  nlohmann::json j;
  j["precision"] = nn::precision_name(s.precision);
  j["stages"] = nlohmann::json::array();
  for (const GenerateStageReport& stage : s.stages)
    j["stages"].push_back({{"name", stage.name},
                           {"seconds", stage.seconds},
                           {"peak_memory_mib", stage.peak_memory_mib},
                           {"resumed", stage.resumed}});
  j["total_seconds"] = s.total_seconds();
  j["mesh"] = mesh_json(s.reconstruction);
  j["written"] = written_json(s.written);
  return j;
}

}  // namespace u3d
