#pragma once
// The options a client of `unique3d serve` may set on a job, from the text fields of its submission
// (docs/server.md lists them): parsed strictly, each checked against the same ranges as the command's
// options, and turned into the facade's request. An unknown field or a bad value is an Error naming it.
#include <filesystem>
#include <map>
#include <string>

#include "server/job.h"

namespace u3d::server {

// The job's spec with its input and output paths inside `folder` (server/job_runner.h's layout):
// reconstruct reads the view set from input/; generate runs the networks of `models` on the photo that
// the caller names in spec.generate.image once it is written.
JobSpec make_job_spec(JobKind kind, const std::map<std::string, std::string>& fields,
                      const std::filesystem::path& folder, const std::filesystem::path& models);

}  // namespace u3d::server
