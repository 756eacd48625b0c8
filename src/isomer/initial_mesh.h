#pragma once
// ISOMER stage (a): the initial mesh (paper Sec. 3.2 "Initial Mesh Estimation").
//
// The front and back normal maps are integrated to height maps (normal_integration.h) and lifted to
// two surface sheets; the side views fix how deep the object is. Screened Poisson reconstruction
// joins the sheets into one closed surface, and quadric decimation brings it to about 2,000 faces.
// The result is closed and manifold and already has the topology visible from the front (holes
// through the object stay holes).
//
// Depth placement. Each sheet's heights are zero on its silhouette rim. The right and left masks
// give the object's z extent [z_min, z_max] directly (their image x axis is world -z / +z), so both
// sheets are scaled by one factor s and the rim placed at z0 such that the front sheet's highest
// point touches z_max and the back sheet's lowest touches z_min. This uses the same information as
// the official code (height scaled by the side view's width/height ratio) but in the views' shared
// orthographic frame, so it also centres the object in depth.
#include "core/mesh.h"
#include "isomer/normal_integration.h"
#include "core/view_set.h"

namespace u3d {

struct InitialMeshOptions {
  int integration_resolution = 192;  // normal maps are resampled to this before integrating (official: 192)
  NormalIntegrationOptions integration;
  int poisson_depth = 6;     // official: screened Poisson depth 6
  int target_faces = 2000;   // official: quadric decimation to 2,000 faces
  float min_component_fraction = 0.01f;  // Poisson islands with fewer faces than this share are dropped
};

// Height maps and placement, exposed for tests and diagnostics.
struct DepthSheets {
  int resolution = 0;
  std::vector<float> front_height, back_height;  // world units toward each view's camera, 0 outside
  std::vector<uint8_t> front_mask, back_mask;
  std::vector<Vec3f> front_normals, back_normals;  // world-space input normals
  float z_min = 0.f, z_max = 0.f;  // object depth range from the side views
  float scale = 1.f;               // s: applied to both height maps
  float rim_z = 0.f;               // z0: world z of the silhouette rim
};

DepthSheets integrate_front_and_back(const ViewSet& views, const InitialMeshOptions& options = {});

// Throws Error if the reconstruction fails (e.g. the views describe no volume).
Mesh build_initial_mesh(const ViewSet& views, const InitialMeshOptions& options = {});

}  // namespace u3d
