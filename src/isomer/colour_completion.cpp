#include "isomer/colour_completion.h"

#include "core/error.h"
#include "geometry/edge_topology.h"

namespace u3d {

ColourCompletionReport complete_vertex_colours(const std::vector<Vec3i>& faces, std::vector<Vec3f>& colours,
                                               const std::vector<uint8_t>& known, int max_rounds) {
  require(colours.size() == known.size(), "colour completion: colours and known flags differ in size");
  const size_t n = colours.size();
  const EdgeTopology topo = build_edge_topology(faces, n);  // unique neighbours: the vertex rings, ascending

  std::vector<int> unknown;
  for (size_t v = 0; v < n; ++v)
    if (!known[v]) unknown.push_back(int(v));
  std::vector<uint8_t> coloured(known.begin(), known.end());
  std::vector<Vec3f> next_colour(unknown.size());
  std::vector<uint8_t> next_coloured(unknown.size());

  ColourCompletionReport report;
  size_t coloured_count = n - unknown.size();
  int pending = 0;  // growth rounds not yet matched by a smoothing round
  bool growing = true;
  for (int round = 0; round < max_rounds && !unknown.empty() && (growing || pending > 0); ++round) {
    for (size_t k = 0; k < unknown.size(); ++k) {
      Vec3f sum(0, 0, 0);
      int count = 0;
      for (int j = topo.ring_offsets[unknown[k]]; j < topo.ring_offsets[unknown[k] + 1]; ++j)
        if (coloured[topo.ring[j]]) sum += colours[topo.ring[j]], ++count;
      next_coloured[k] = count > 0;
      next_colour[k] = count > 0 ? Vec3f(sum / float(count)) : colours[unknown[k]];
    }
    size_t now = n - unknown.size();
    for (size_t k = 0; k < unknown.size(); ++k) {
      colours[unknown[k]] = next_colour[k];
      coloured[unknown[k]] = next_coloured[k];
      now += next_coloured[k];
    }
    if (growing && now > coloured_count) {
      coloured_count = now;
      ++pending;
      ++report.growth_rounds;
    } else {
      growing = false;
      --pending;
      ++report.smoothing_rounds;
    }
  }
  for (int v : unknown) (coloured[v] ? report.filled : report.unreachable)++;
  return report;
}

}  // namespace u3d
