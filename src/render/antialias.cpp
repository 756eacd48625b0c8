#include "render/antialias.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace u3d {

EdgeNeighbors edge_neighbors(const std::vector<Vec3i>& faces, const EdgeTopology& topology) {
  EdgeNeighbors n;
  n.opposite.resize(faces.size());
  const int64_t face_count = int64_t(faces.size());
  // The lookups are independent: split them over the threads (the renderer calls this every frame).
#pragma omp parallel for schedule(static) if (face_count > 16384)
  for (int64_t fi = 0; fi < face_count; ++fi) {
    const Vec3i& f = faces[fi];
    for (int i = 0; i < 3; ++i) {
      // The edge opposite corner i is side i + 1 (from f[i + 1] to f[i + 2]); the neighbour is the
      // side in the other direction.
      const int side = (i + 1) % 3, e = topology.face_edges[fi][side];
      const int other = topology.edge_sides[e][f[side] == topology.edge_vertices[e][0] ? 1 : 0];
      n.opposite[fi][i] = other < 0 ? -1 : faces[other / 3][(other % 3 + 2) % 3];
    }
  }
  return n;
}

namespace {

inline bool same_sign(float a, float b) { return std::signbit(a) == std::signbit(b); }
inline float cross2(float ax, float ay, float bx, float by) { return ax * by - ay * bx; }

// Per face, bit i set when the edge opposite corner i is a silhouette in this view: the neighbouring
// face folds back onto the same side of it, i.e. the "wing" triangle (opposite vertex, edge) has the
// same screen orientation as the face. Border edges always are. Face f's bits are at mask[f + 1] and
// mask[0] = 0 stands for the background (face id -1), so pixel scans look up any face id unchecked.
void silhouette_edges(const std::vector<Vec3i>& faces, const EdgeNeighbors& neighbors, const ScreenProjection& proj,
                      std::vector<uint8_t>& mask) {
  mask.resize(faces.size() + 1);
  mask[0] = 0;
  for (size_t fi = 0; fi < faces.size(); ++fi) {
    const Vec3i& f = faces[fi];
    const Vec2f p[3] = {proj.pixel[f[0]], proj.pixel[f[1]], proj.pixel[f[2]]};
    const float bb = cross2(p[1].x() - p[0].x(), p[1].y() - p[0].y(), p[2].x() - p[0].x(), p[2].y() - p[0].y());
    uint8_t bits = 0;
    for (int i = 0; i < 3; ++i) {
      const int o = neighbors.opposite[fi][i];
      if (o < 0) {
        bits |= uint8_t(1u << i);
        continue;
      }
      const Vec2f& q = proj.pixel[o];
      const Vec2f& a = p[(i + 1) % 3];
      const Vec2f& b = p[(i + 2) % 3];
      if (same_sign(cross2(a.x() - q.x(), a.y() - q.y(), b.x() - q.x(), b.y() - q.y()), bb)) bits |= uint8_t(1u << i);
    }
    mask[fi + 1] = bits;
  }
}

// Analyses one pair of neighbouring pixels; returns false when nothing is blended.
bool analyse_pair(const RasterBuffer& raster, const std::vector<Vec3i>& faces, const uint8_t* silhouette,
                  const ScreenProjection& proj, int32_t p0, int32_t p1, bool down, AntialiasPair& out) {
  const int32_t t0 = raster.face_id[p0], t1 = raster.face_id[p1];
  // The nearer triangle owns the edge (the far one is occluded there, or background).
  int32_t tri = t0 >= 0 ? t0 : t1;
  if (t0 >= 0 && t1 >= 0) tri = raster.depth[p0] < raster.depth[p1] ? t0 : t1;
  const uint8_t sil = silhouette[tri];
  if (!sil) return false;
  const bool from1 = tri != t0;
  const int32_t origin = from1 ? p1 : p0;
  const float fx = float(origin % raster.width) + 0.5f, fy = float(origin / raster.width) + 0.5f;
  const Vec3i& f = faces[tri];
  float x[3], y[3];
  for (int i = 0; i < 3; ++i) {
    x[i] = proj.pixel[f[i]].x() - fx;
    y[i] = proj.pixel[f[i]].y() - fy;
  }
  if (down)
    for (int i = 0; i < 3; ++i) std::swap(x[i], y[i]);
  // Now the neighbour lies along +x (or -x when the triangle is in pixel1): find where the edges
  // cross the x axis and keep the crossing farthest toward the neighbour.
  const float ds = from1 ? -1.f : 1.f;
  int best = -1;
  float best_c = -std::numeric_limits<float>::infinity();
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    if (same_sign(y[j], y[k])) continue;
    const float dy = y[k] - y[j];
    if (dy == 0.f) continue;
    const float c = ds * (x[j] * dy - y[j] * (x[k] - x[j])) / dy;
    if (c > best_c) best_c = c, best = i;
  }
  if (best < 0 || !(sil & (1u << best))) return false;
  {
    const int j = (best + 1) % 3, k = (best + 2) % 3;
    // Edges closer to horizontal are handled by the perpendicular pixel pairs.
    if (std::abs(y[k] - y[j]) < std::abs(x[k] - x[j])) return false;
  }
  constexpr float kEps = 0.0625f;  // tolerate 1/16 pixel of inaccuracy in the raster
  if (!(best_c > -kEps && best_c < 1.f + kEps)) return false;
  const float dc = std::clamp(best_c, 0.f, 1.f);
  out = {p0, p1, tri, int8_t(best), down, from1, ds * (0.5f - dc)};
  return out.alpha != 0.f;
}

}  // namespace

std::vector<AntialiasPair> find_antialias_pairs(const RasterBuffer& raster, const std::vector<Vec3i>& faces,
                                                const EdgeNeighbors& neighbors, const ScreenProjection& projection) {
  std::vector<AntialiasPair> pairs;
  find_antialias_pairs(raster, faces, neighbors, projection, pairs);
  return pairs;
}

void find_antialias_pairs(const RasterBuffer& raster, const std::vector<Vec3i>& faces, const EdgeNeighbors& neighbors,
                          const ScreenProjection& projection, std::vector<AntialiasPair>& pairs) {
  pairs.clear();
  thread_local std::vector<uint8_t> silhouette_storage;  // per view and frame: kept, not reallocated
  silhouette_edges(faces, neighbors, projection, silhouette_storage);
  const uint8_t* silhouette = silhouette_storage.data() + 1;  // indexable by face id, -1 included
  const int w = raster.width, h = raster.height;
  // Pairs differ in face id, so both pixels are background outside the footprint grown by one pixel.
  const PixelRect& r = raster.footprint;
  // Most pairs that differ in face id are interior edges between two faces with no silhouette edge:
  // the edge found is always one of the nearer face's, so those are skipped before any analysis. The
  // test is computed without branches: whether neighbouring ids differ is a coin flip inside the
  // footprint, while a pair worth analysing is rare, so only that last test branches.
  AntialiasPair pair;
  for (int y = std::max(r.y0 - 1, 0); y <= r.y1; ++y) {
    const int32_t* row = raster.face_id.data() + size_t(y) * w;
    const int32_t* below = y + 1 < h ? row + w : row;  // the last row compares with itself: no pairs
    const int x_end = std::min(r.x1, w - 2);  // pixels with a right neighbour
    for (int x = std::max(r.x0 - 1, 0); x <= r.x1; ++x) {
      const int32_t a = row[x], right = x <= x_end ? row[x + 1] : a, down = below[x];
      const uint8_t own = silhouette[a];
      const bool across = (a != right) & ((own | silhouette[right]) != 0);
      const bool along = (a != down) & ((own | silhouette[down]) != 0);
      if (!(across | along)) continue;
      const int32_t p = y * w + x;
      if (across && analyse_pair(raster, faces, silhouette, projection, p, p + 1, false, pair)) pairs.push_back(pair);
      if (along && analyse_pair(raster, faces, silhouette, projection, p, p + w, true, pair)) pairs.push_back(pair);
    }
  }
}

void apply_antialias(const std::vector<AntialiasPair>& pairs, const Image& color, Image& out) {
  const int ch = color.channels;
  for (const AntialiasPair& a : pairs) {
    const float* c0 = color.data.data() + size_t(a.pixel0) * ch;
    const float* c1 = color.data.data() + size_t(a.pixel1) * ch;
    float* o = out.data.data() + size_t(a.alpha > 0.f ? a.pixel0 : a.pixel1) * ch;
    for (int c = 0; c < ch; ++c) o[c] += a.alpha * (c1[c] - c0[c]);
  }
}

void antialias_backward(const std::vector<AntialiasPair>& pairs, const Image& color, const std::vector<Vec3i>& faces,
                        const ScreenProjection& projection, const Image& grad_out, Image& grad_color,
                        ScreenGradient& screen) {
  const int ch = color.channels;
  const int width = int(projection.width);
  for (const AntialiasPair& a : pairs) {
    const float* c0 = color.data.data() + size_t(a.pixel0) * ch;
    const float* c1 = color.data.data() + size_t(a.pixel1) * ch;
    const float* g = grad_out.data.data() + size_t(a.alpha > 0.f ? a.pixel0 : a.pixel1) * ch;
    float* g0 = grad_color.data.data() + size_t(a.pixel0) * ch;
    float* g1 = grad_color.data.data() + size_t(a.pixel1) * ch;
    float dd = 0.f;  // dL/d(alpha)
    for (int c = 0; c < ch; ++c) {
      dd += g[c] * (c1[c] - c0[c]);
      g0[c] -= a.alpha * g[c];
      g1[c] += a.alpha * g[c];
    }
    // A clamped crossing (|alpha| = 1/2) does not move with the edge.
    if (dd == 0.f || std::abs(a.alpha) >= 0.5f) continue;
    const Vec3i& f = faces[a.face];
    const int v1 = f[(a.edge + 1) % 3], v2 = f[(a.edge + 2) % 3];
    const int32_t origin = a.from_pixel1 ? a.pixel1 : a.pixel0;
    const float fx = float(origin % width) + 0.5f, fy = float(origin / width) + 0.5f;
    float x1 = projection.pixel[v1].x() - fx, y1 = projection.pixel[v1].y() - fy;
    float x2 = projection.pixel[v2].x() - fx, y2 = projection.pixel[v2].y() - fy;
    if (a.down) std::swap(x1, y1), std::swap(x2, y2);
    const float d = y2 - y1;
    if (std::abs(d) < 1e-6f) continue;
    // alpha = ds/2 - x_cross with x_cross = (x1 y2 - x2 y1) / (y2 - y1), the edge's x-axis crossing.
    const float xc = (x1 * y2 - x2 * y1) / d;
    const float gx = -dd;  // dL/d(x_cross)
    Vec2f g1v(gx * y2 / d, gx * (xc - x2) / d);
    Vec2f g2v(-gx * y1 / d, gx * (x1 - xc) / d);
    if (a.down) std::swap(g1v.x(), g1v.y()), std::swap(g2v.x(), g2v.y());
    screen.pixel[v1] += g1v;
    screen.pixel[v2] += g2v;
  }
}

}  // namespace u3d
