// Connected pieces of a grid's inside (geometry/grid_components.h).
#include <gtest/gtest.h>

#include "geometry/grid_components.h"

namespace u3d {
namespace {

ScalarGrid empty_grid(int n) {
  ScalarGrid grid;
  grid.nx = grid.ny = grid.nz = n;
  grid.values.assign(size_t(n) * n * n, -1.f);
  return grid;
}

void fill(ScalarGrid& grid, int x0, int y0, int z0, int x1, int y1, int z1) {
  for (int z = z0; z <= z1; ++z)
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) grid.values[grid.index(x, y, z)] = 1.f;
}

TEST(GridComponents, CountsSeparateSolidsSixConnected) {
  ScalarGrid grid = empty_grid(12);
  EXPECT_EQ(count_inside_components(grid), 0);
  fill(grid, 1, 1, 1, 4, 4, 4);
  EXPECT_EQ(count_inside_components(grid), 1);
  fill(grid, 7, 1, 1, 9, 2, 3);  // apart from the first
  EXPECT_EQ(count_inside_components(grid), 2);
  fill(grid, 5, 2, 2, 6, 2, 2);  // a bar joins them
  EXPECT_EQ(count_inside_components(grid), 1);
  fill(grid, 5, 5, 5, 5, 5, 5);  // touches the first only at a corner: a piece of its own
  EXPECT_EQ(count_inside_components(grid), 2);
  grid.values[grid.index(11, 11, 11)] = 0.f;  // zero is outside
  EXPECT_EQ(count_inside_components(grid), 2);
}

TEST(GridComponents, LabelsEachSampleWithItsPiece) {
  ScalarGrid grid = empty_grid(8);
  fill(grid, 1, 1, 1, 2, 2, 2);
  fill(grid, 5, 5, 5, 6, 6, 6);
  int count = 0;
  const std::vector<int> label = label_inside_components(grid, &count);
  EXPECT_EQ(count, 2);
  EXPECT_EQ(label[grid.index(0, 0, 0)], -1);
  EXPECT_EQ(label[grid.index(1, 1, 1)], 0);  // numbered in the order of their first samples
  EXPECT_EQ(label[grid.index(2, 2, 2)], 0);
  EXPECT_EQ(label[grid.index(5, 5, 5)], 1);
  EXPECT_EQ(label[grid.index(6, 6, 6)], 1);
}

}  // namespace
}  // namespace u3d
