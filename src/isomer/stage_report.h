#pragma once
// What an ISOMER optimisation stage reports: its final loss and edge length, and where its time went;
// and the named stage times a run reports (the network stages use them too).
#include <string>

namespace u3d {

struct StageTiming {
  std::string name;
  double seconds = 0.0;
};

// Seconds spent in each part of the step loop (optimisation_loop.h), summed over the steps.
struct StageProfile {
  double render = 0.0;    // rasterize, interpolate, anti-alias (all views)
  double losses = 0.0;    // the stage's loss terms, including target updates
  double backward = 0.0;  // image gradients -> vertex positions
  double step = 0.0;      // vertex normals + optimizer update
  double remesh = 0.0;    // collapse / split / flip
};

struct StageReport {
  int steps = 0;
  double seconds = 0.0;
  double final_loss = 0.0;
  float final_edge_length = 0.f;
  StageProfile profile;
};

}  // namespace u3d
