#pragma once
// Colours for vertices no view saw (paper appendix, "Efficient Invisible Region Color Completion").
//
// Colours spread from the known vertices over the mesh edges in simultaneous (Jacobi) rounds: each
// round, every unknown vertex with at least one coloured neighbour takes the mean colour of its
// coloured neighbours and counts as coloured from then on. Stopping as soon as everything is reached
// would leave a hard seam where two fronts meet, so, as the paper asks and the official code does,
// the rounds go on once the coloured set stops growing, as many extra rounds as it took to grow it
// (the official count-up/count-down rule), letting the colours diffuse into a smooth gradient.
// Known vertices never change.
#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace u3d {

struct ColorCompletionReport {
  int growth_rounds = 0;      // rounds until the coloured set stopped growing
  int smoothing_rounds = 0;   // extra rounds after that
  size_t filled = 0;          // unknown vertices that received a colour
  size_t unreachable = 0;     // unknown vertices with no path to a known one (colour left as given)
};

// colours: per vertex; entries of unknown vertices are used only if they stay unreachable (give a
// neutral fallback there). known: nonzero = fixed colour.
ColorCompletionReport complete_vertex_colors(const std::vector<Vec3i>& faces, std::vector<Vec3f>& colors,
                                               const std::vector<uint8_t>& known, int max_rounds = 10000);

}  // namespace u3d
