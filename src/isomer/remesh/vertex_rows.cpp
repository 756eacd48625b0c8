#include "isomer/remesh/vertex_rows.h"

namespace u3d {

int VertexRows::append_mean(int a, int b) {
  const int index = int(count());
  values.resize(values.size() + size_t(stride));
  const float* ra = row(a);
  const float* rb = row(b);
  float* out = row(index);
  for (int k = 0; k < stride; ++k) out[k] = 0.5f * (ra[k] + rb[k]);
  return index;
}

void VertexRows::average_into(int a, int b) {
  float* ra = row(a);
  const float* rb = row(b);
  for (int k = 0; k < stride; ++k) ra[k] = 0.5f * (ra[k] + rb[k]);
}

}  // namespace u3d
