#pragma once
// Which points of a surface a camera outside it can see. Some ground-truth models carry surface that no
// photograph shows: a face left running under another part (the avocado's cut face continues under its
// stone), the walls of a closed-off cavity. A reconstruction from images cannot have that surface, so
// completeness and recall are also reported over the visible GT samples alone (docs/evaluation.md).
#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "geometry/surface_sampling.h"

namespace u3d {

struct VisibilityOptions {
  int directions = 64;    // orthographic views, evenly spread over the sphere of directions
  int resolution = 1024;  // pixels per side of each view's depth buffer
};

// Per sample (1 = visible): seen by at least one of the views, i.e. at its pixel nothing lies in front
// of it by more than two pixel widths. Both sides of every face are seen (GT models are often open or
// inconsistently oriented). Throws Error on an empty mesh.
std::vector<uint8_t> visible_from_outside(const Mesh& mesh, const SurfaceSamples& samples,
                                          const VisibilityOptions& options = {});

// `count` unit directions spread evenly over the sphere (a Fibonacci lattice; none exactly at a pole).
std::vector<Vec3f> sphere_directions(int count);

}  // namespace u3d
