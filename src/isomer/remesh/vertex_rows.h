#pragma once
// Per-vertex data that travels with the vertices through remeshing: position first (3 floats), then
// any state (the optimizer's moments and reference edge length). Row-major, one row per vertex, so an
// edit averages whole rows: a new vertex inherits the mean state of the vertices it replaces.
#include <cstddef>
#include <vector>

#include "core/mesh.h"

namespace u3d {

struct VertexRows {
  int stride = 3;
  std::vector<float> values;

  size_t count() const { return values.size() / size_t(stride); }
  float* row(size_t v) { return values.data() + v * size_t(stride); }
  const float* row(size_t v) const { return values.data() + v * size_t(stride); }
  Vec3f position(size_t v) const { return Vec3f(row(v)[0], row(v)[1], row(v)[2]); }

  // Appends the mean of rows a and b; returns its index.
  int append_mean(int a, int b);
  // Row a becomes the mean of rows a and b.
  void average_into(int a, int b);
};

}  // namespace u3d
