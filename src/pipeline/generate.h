#pragma once
// The library's facade for the whole method: one photo in, a coloured mesh out (`unique3d generate`).
// The stages, with the official defaults (docs/generate.md):
//   prepare    the photo checked, its background removed when it has none, cropped to the object and
//              padded to a square on white                                    -> front.png
//   multiview  four 256 px views from the multi-view model                    -> multiview/
//   refine     the views redrawn as a 1024 px 2x2 grid (ControlNet-tile), or
//              resized to the size it gives (Lanczos) without refinement      -> refined/
//   upscale    the views to 2048 px (Real-ESRGAN x4)                          -> upscaled/
//   normals    a normal map per view, masks, world space: the view set        -> views/
//   reconstruct ISOMER on the view set                                        -> the output mesh
// Each network stage loads its models when it starts and frees them when it ends, unless the caller
// passes a NetworkCache that keeps them for its next run (pipeline/network_cache.h). With
// keep_intermediates every stage's outputs are written to that folder as it finishes; with
// from_intermediates the run resumes after the last stage whose outputs are all in that folder.
#include <filesystem>
#include <string>
#include <vector>

#include "core/progress.h"
#include "isomer/reconstruct.h"
#include "pipeline/image_stages.h"
#include "pipeline/multiview_stage.h"
#include "pipeline/network_cache.h"
#include "pipeline/network_stage.h"
#include "pipeline/normal_stage.h"
#include "pipeline/reconstruct.h"

namespace u3d {

struct GenerateRequest {
  std::filesystem::path image;   // the photo (PNG/JPEG; RGBA with the object on transparency, or not); not
                                 // read, and may be empty, when resuming from_intermediates
  std::filesystem::path output;  // .glb, .obj or .ply; empty: none written (the summary holds the mesh)
  bool previews = false;         // as ReconstructRequest: also <stem>_views.png and <stem>_turntable.png
  NetworkOptions network;
  bool raw_matte = false;                    // as run_prepare_stage (pipeline/image_stages.h)
  bool refine = true;                        // false: the views are resized instead of refined
  std::filesystem::path keep_intermediates;  // empty: none written
  std::filesystem::path from_intermediates;  // empty: start from the photo
  MultiViewOptions multiview;
  RefineOptions refine_options;
  NormalOptions normals;
  ReconstructOptions reconstruct;
  bool official_output_scale = false;                 // as ReconstructRequest
  TextureFormat texture_format = TextureFormat::Png;  // as ReconstructRequest
};

struct GenerateStageReport {
  std::string name;              // "prepare", "multiview", ...
  double seconds = 0.0;          // 0 when resumed
  double peak_memory_mib = 0.0;  // the process's peak resident memory while the stage ran (0 when resumed;
                                 // MemoryPeakWatch, pipeline/network_stage.h)
  bool resumed = false;          // its outputs were read from from_intermediates
};

struct GenerateSummary {
  nn::Precision precision = nn::Precision::kFp32;
  std::vector<GenerateStageReport> stages;
  ReconstructSummary reconstruction;
  std::vector<std::filesystem::path> written;  // the mesh and the intermediates
  // The process's peak resident memory when the run ended (VmHWM: what `/usr/bin/time -v` reports).
  double peak_memory_mib = 0.0;
  double total_seconds() const;
};

// The stage names in order, as GenerateStageReport::name uses them.
const std::vector<std::string>& generate_stage_names();

// Checks the request, the photo and the model files of the stages that will run before any long work
// (Error naming the file or value), runs the stages, and writes the mesh only after all succeeded.
// With `networks`, the stages take their networks from it and leave them there for the next run.
GenerateSummary generate(const GenerateRequest& request, ProgressListener* listener = nullptr,
                         NetworkCache* networks = nullptr);

}  // namespace u3d
