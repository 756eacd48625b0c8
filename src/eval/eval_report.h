#pragma once
// Presentation of an EvalReport: a short human-readable summary and a JSON document (field names and
// units in docs/evaluation.md).
#include <nlohmann/json.hpp>
#include <string>

#include "eval/evaluate.h"

namespace u3d {

nlohmann::json report_to_json(const EvalReport& report);
std::string report_summary(const EvalReport& report);

}  // namespace u3d
