#include "server/job_runner.h"

#include <chrono>
#include <fstream>
#include <map>
#include <set>
#include <system_error>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "io/mesh_io.h"
#include "pipeline/summary_json.h"
#include "server/zip_archive.h"

namespace u3d::server {

namespace fs = std::filesystem;

fs::path job_input_dir(const fs::path& folder) { return folder / "input"; }
fs::path job_result_dir(const fs::path& folder) { return folder / "result"; }
fs::path job_intermediates_dir(const fs::path& folder) { return folder / "intermediates"; }
fs::path job_mesh_path(const fs::path& folder) { return job_result_dir(folder) / "mesh.glb"; }

namespace {

// The facade's events as the job's: stages as they begin and end, a loop's steps (at most a few a
// second, with the time left), messages, and the intermediates a generate stage wrote, as files. Paths
// in the job's folder are shown by their names in it.
class JobProgress : public ProgressListener {
 public:
  explicit JobProgress(Job& job) : job_(job) {}

  void on_event(const ProgressEvent& e) override {
    using Kind = ProgressEvent::Kind;
    const auto now = Clock::now();
    switch (e.kind) {
      case Kind::StageBegin:
        stage_begin_ = loop_begin_ = now;
        loop_.clear();
        job_.add_event("stage", {{"name", local(e.text)}, {"state", "begin"}});
        break;
      case Kind::StageEnd:
        job_.add_event("stage", {{"name", local(e.text)}, {"state", "end"}, {"seconds", e.seconds}});
        publish_intermediates();
        break;
      case Kind::Message: job_.add_event("message", {{"text", local(e.text)}}); break;
      case Kind::Step: {
        if (e.text != loop_) {
          loop_ = e.text;
          loop_begin_ = last_step_ == 0 ? stage_begin_ : last_step_time_;
        }
        last_step_ = e.step;
        last_step_time_ = now;
        const bool edge = e.step == 1 || e.step == e.steps;
        if (!edge && now - last_sent_ < std::chrono::milliseconds(250)) break;
        last_sent_ = now;
        const double elapsed = std::chrono::duration<double>(now - loop_begin_).count();
        nlohmann::json data = {{"stage", e.text}, {"step", e.step}, {"steps", e.steps}};
        if (e.step > 0 && e.steps >= e.step) data["seconds_left"] = elapsed / e.step * (e.steps - e.step);
        job_.add_event("step", std::move(data));
        break;
      }
    }
  }

  bool cancel_requested() override { return job_.cancel_requested(); }

  // Every intermediate written so far becomes a file of the job, named by its path in the folder
  // ("views/front_normal.png" -> "views_front_normal.png"). Temporary files start with a dot.
  void publish_intermediates() {
    const fs::path dir = job_intermediates_dir(job_.folder());
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return;
    std::set<fs::path> found;
    for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      if (it->path().filename().string().front() == '.') {
        if (it->is_directory(ec)) it.disable_recursion_pending();
        continue;
      }
      if (it->is_regular_file(ec)) found.insert(it->path());
    }
    for (const fs::path& path : found) {
      std::string name = fs::relative(path, dir, ec).generic_string();
      for (char& c : name)
        if (c == '/') c = '_';
      job_.add_file(name, path);
    }
  }

 private:
  using Clock = std::chrono::steady_clock;
  std::string local(std::string text) const { return without_folder(std::move(text), job_.folder()); }

  Job& job_;
  Clock::time_point stage_begin_ = Clock::now(), loop_begin_ = Clock::now(), last_step_time_ = Clock::now();
  Clock::time_point last_sent_{};
  std::string loop_;
  int last_step_ = 0;
};

void write_json(const fs::path& path, const nlohmann::json& j) {
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << j.dump(2) << "\n";
    f.close();
    require(bool(f), "cannot write " + path.string());
  });
}

// The mesh as OBJ (with its material and texture) in one zip, for tools that do not read GLB.
void write_obj_zip(const Mesh& mesh, const ReconstructRequest& like, const fs::path& zip_path) {
  const fs::path dir = zip_path.parent_path() / ".obj";
  fs::create_directories(dir);
  Mesh scaled = mesh;
  if (like.official_output_scale)
    for (Vec3f& p : scaled.positions) p *= kOfficialOutputScale;
  write_mesh(scaled, dir / "mesh.obj", {like.texture_format});
  std::vector<std::pair<std::string, fs::path>> files;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.is_regular_file() && entry.path().filename().string().front() != '.')
      files.emplace_back(entry.path().filename().string(), entry.path());
  write_zip(zip_path, files);
  fs::remove_all(dir);
}

// summary.json: the facade's summary, with the files by their names in the job's folder.
nlohmann::json job_summary(nlohmann::json summary, const fs::path& folder) {
  nlohmann::json written = nlohmann::json::array();
  for (const auto& path : summary["written"]) {
    std::error_code ec;
    written.push_back(fs::relative(path.get<std::string>(), folder, ec).generic_string());
  }
  summary["written"] = written;
  return summary;
}

void run(Job& job, const JobSpec& spec, JobProgress& progress) {
  const fs::path result = job_result_dir(job.folder());
  fs::create_directories(result);
  const Mesh* mesh = nullptr;
  const ReconstructRequest* mesh_request = &spec.reconstruct;
  ReconstructSummary reconstructed;
  GenerateSummary generated;
  nlohmann::json summary;
  ReconstructRequest generate_like;
  if (spec.kind == JobKind::Reconstruct) {
    reconstructed = reconstruct_folder(spec.reconstruct, &progress);
    mesh = &reconstructed.mesh;
    summary = summary_json(reconstructed);
  } else {
    generated = generate(spec.generate, &progress);
    progress.publish_intermediates();
    mesh = &generated.reconstruction.mesh;
    summary = summary_json(generated);
    generate_like.official_output_scale = spec.generate.official_output_scale;
    generate_like.texture_format = spec.generate.texture_format;
    mesh_request = &generate_like;
  }
  ProgressScope scope(&progress);
  {
    StageTimer timer("writing mesh_obj.zip");
    write_obj_zip(*mesh, *mesh_request, result / "mesh_obj.zip");
  }
  write_json(result / "summary.json", job_summary(summary, job.folder()));
  job.set_summary(job_summary(summary, job.folder()));
  for (const char* name : {"mesh.glb", "mesh_views.png", "mesh_turntable.png", "mesh_obj.zip", "summary.json"})
    if (fs::exists(result / name)) job.add_file(name, result / name);
}

}  // namespace

void run_job(Job& job) { run_job_as(job, job.spec()); }

void run_job_as(Job& job, const JobSpec& spec) {
  JobProgress progress(job);
  try {
    run(job, spec, progress);
  } catch (...) {
    // A failed or cancelled job keeps nothing: no result, no intermediates, no input.
    std::error_code ec;
    fs::remove_all(job.folder(), ec);
    throw;
  }
}

}  // namespace u3d::server
