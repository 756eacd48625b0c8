#pragma once
// The summaries of the facade's whole runs as JSON: `generate --json`, the summary.json of a job of
// `unique3d serve`, and scripts read the same fields (docs/server.md lists them).
#include <nlohmann/json.hpp>

#include "pipeline/generate.h"
#include "pipeline/reconstruct.h"

namespace u3d {

// {mesh: {vertices, faces, components, watertight, topology, silhouette_iou: [4]}, colouring: {confident,
// completed, unreachable}, texture: {charts, texel_efficiency} (with a texture), timings: [{name,
// seconds}], total_seconds, written: [paths]}.
nlohmann::json summary_json(const ReconstructSummary& summary);

// {precision, stages: [{name, seconds, peak_memory_mib, resumed}], total_seconds, mesh: as above, written}.
nlohmann::json summary_json(const GenerateSummary& summary);

}  // namespace u3d
