#include "isomer/color_completion.h"

#include "core/error.h"
#include "geometry/edge_topology.h"

namespace u3d {

ColorCompletionReport complete_vertex_colors(const std::vector<Vec3i>& faces, std::vector<Vec3f>& colors,
                                               const std::vector<uint8_t>& known, int max_rounds) {
  require(colors.size() == known.size(), "colour completion: colours and known flags differ in size");
  const size_t n = colors.size();
  const EdgeTopology topo = build_edge_topology(faces, n);  // unique neighbours: the vertex rings, ascending

  std::vector<int> unknown;
  for (size_t v = 0; v < n; ++v)
    if (!known[v]) unknown.push_back(int(v));
  std::vector<uint8_t> colored(known.begin(), known.end());
  std::vector<Vec3f> next_color(unknown.size());
  std::vector<uint8_t> next_colored(unknown.size());

  ColorCompletionReport report;
  size_t colored_count = n - unknown.size();
  int pending = 0;  // growth rounds not yet matched by a smoothing round
  bool growing = true;
  for (int round = 0; round < max_rounds && !unknown.empty() && (growing || pending > 0); ++round) {
    for (size_t k = 0; k < unknown.size(); ++k) {
      Vec3f sum(0, 0, 0);
      int count = 0;
      for (int j = topo.ring_offsets[unknown[k]]; j < topo.ring_offsets[unknown[k] + 1]; ++j)
        if (colored[topo.ring[j]]) sum += colors[topo.ring[j]], ++count;
      next_colored[k] = count > 0;
      next_color[k] = count > 0 ? Vec3f(sum / float(count)) : colors[unknown[k]];
    }
    size_t now = n - unknown.size();
    for (size_t k = 0; k < unknown.size(); ++k) {
      colors[unknown[k]] = next_color[k];
      colored[unknown[k]] = next_colored[k];
      now += next_colored[k];
    }
    if (growing && now > colored_count) {
      colored_count = now;
      ++pending;
      ++report.growth_rounds;
    } else {
      growing = false;
      --pending;
      ++report.smoothing_rounds;
    }
  }
  for (int v : unknown) (colored[v] ? report.filled : report.unreachable)++;
  return report;
}

}  // namespace u3d
