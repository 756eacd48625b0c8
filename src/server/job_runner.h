#pragma once
// Runs a job of `unique3d serve` through the library facade (pipeline/reconstruct.h, pipeline/generate.h)
// with a progress listener that turns the facade's events into the job's event stream and polls the
// job's cancellation. A job's folder:
//   input/          what the client uploaded, under the server's own names (server/job_inputs.h)
//   intermediates/  generate: every stage's outputs as it ends (docs/generate.md)
//   result/         mesh.glb, mesh_views.png, mesh_turntable.png, mesh_obj.zip, summary.json
// Each result file and intermediate becomes fetchable (a "file" event) as soon as it is written. A job
// that fails or is cancelled leaves no folder behind.
#include <filesystem>

#include "server/job.h"

namespace u3d::server {

// The mesh a job writes and the folders above, for a job whose folder is `folder`.
std::filesystem::path job_input_dir(const std::filesystem::path& folder);
std::filesystem::path job_result_dir(const std::filesystem::path& folder);
std::filesystem::path job_intermediates_dir(const std::filesystem::path& folder);
std::filesystem::path job_mesh_path(const std::filesystem::path& folder);

// Runs `job` to its end (JobRunner of server/job_queue.h).
void run_job(Job& job);

// The same with `spec` in place of the job's own (its folder, events and cancellation stay the job's):
// for callers that set what the options a client may send cannot, such as the tests, which run the tiny
// stand-in networks at their small sizes.
void run_job_as(Job& job, const JobSpec& spec);

}  // namespace u3d::server
