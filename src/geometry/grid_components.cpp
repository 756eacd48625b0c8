#include "geometry/grid_components.h"

#include "core/error.h"

namespace u3d {

int count_inside_components(const ScalarGrid& grid) {
  require(grid.nx >= 0 && grid.ny >= 0 && grid.nz >= 0 &&
              grid.values.size() == size_t(grid.nx) * size_t(grid.ny) * size_t(grid.nz),
          "grid components: the grid's values do not match its size");
  // 1: inside and not reached yet; 2: reached by a flood fill.
  std::vector<uint8_t> state(grid.values.size());
  for (size_t i = 0; i < state.size(); ++i) state[i] = grid.values[i] > 0.f;
  int components = 0;
  std::vector<size_t> stack;
  const size_t nx = size_t(grid.nx), nxy = nx * size_t(grid.ny);
  for (size_t start = 0; start < state.size(); ++start) {
    if (state[start] != 1) continue;
    ++components;
    state[start] = 2;
    stack.push_back(start);
    while (!stack.empty()) {
      const size_t i = stack.back();
      stack.pop_back();
      const int x = int(i % nx), y = int(i / nx % size_t(grid.ny)), z = int(i / nxy);
      auto visit = [&](bool exists, size_t j) {
        if (exists && state[j] == 1) state[j] = 2, stack.push_back(j);
      };
      visit(x > 0, i - 1);
      visit(x + 1 < grid.nx, i + 1);
      visit(y > 0, i - nx);
      visit(y + 1 < grid.ny, i + nx);
      visit(z > 0, i - nxy);
      visit(z + 1 < grid.nz, i + nxy);
    }
  }
  return components;
}

}  // namespace u3d
