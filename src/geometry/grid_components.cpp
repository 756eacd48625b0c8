#include "geometry/grid_components.h"

#include "core/error.h"

namespace u3d {

std::vector<int> label_inside_components(const ScalarGrid& grid, int* count) {
  require(grid.nx >= 0 && grid.ny >= 0 && grid.nz >= 0 &&
              grid.values.size() == size_t(grid.nx) * size_t(grid.ny) * size_t(grid.nz),
          "grid components: the grid's values do not match its size");
  std::vector<int> label(grid.values.size(), -1);
  int components = 0;
  std::vector<size_t> stack;
  const size_t nx = size_t(grid.nx), nxy = nx * size_t(grid.ny);
  for (size_t start = 0; start < label.size(); ++start) {
    if (grid.values[start] <= 0.f || label[start] >= 0) continue;
    label[start] = components;
    stack.push_back(start);
    while (!stack.empty()) {
      const size_t i = stack.back();
      stack.pop_back();
      const int x = int(i % nx), y = int(i / nx % size_t(grid.ny)), z = int(i / nxy);
      auto visit = [&](bool exists, size_t j) {
        if (exists && grid.values[j] > 0.f && label[j] < 0) label[j] = components, stack.push_back(j);
      };
      visit(x > 0, i - 1);
      visit(x + 1 < grid.nx, i + 1);
      visit(y > 0, i - nx);
      visit(y + 1 < grid.ny, i + nx);
      visit(z > 0, i - nxy);
      visit(z + 1 < grid.nz, i + nxy);
    }
    ++components;
  }
  if (count) *count = components;
  return label;
}

int count_inside_components(const ScalarGrid& grid) {
  int components = 0;
  label_inside_components(grid, &components);
  return components;
}

}  // namespace u3d
