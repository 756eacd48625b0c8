// Tile-based software rasterizer. Stages (each parallel with OpenMP):
//   1. vertices -> clip space, camera depth, fixed-point pixel position, clip outcode;
//   2. faces -> screen triangles (oriented, culled, pixel bounding box); faces crossing the near/far
//      planes or the guard band are clipped in homogeneous space into a fan of sub-triangles;
//   3. triangles binned into 32x32-pixel tiles (counting sort, deterministic order);
//   4. tiles rasterized independently, so no two threads ever touch the same pixel.
// Edge functions use 8-bit sub-pixel fixed point in 64-bit integers: the top-left rule is exact, so
// triangles sharing an edge (same snapped vertices) cover every pixel centre exactly once.
#include "render/rasterizer.h"

#include <omp.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace u3d {

namespace {

constexpr int kSubpixelBits = 8;
constexpr int64_t kSubpixel = int64_t(1) << kSubpixelBits;
constexpr int64_t kHalfPixel = kSubpixel / 2;
constexpr int kTileBits = 5;
constexpr int kTileSize = 1 << kTileBits;
// Triangles at most this many pixels wide (within a tile) test every pixel of their bounding box;
// wider ones solve each row for its covered span.
constexpr int kNarrowSpan = 8;
// Triangles at most this many pixels across (and within a tile) are tested as one block of SSE2 lanes.
constexpr int kBlockSize = 8;
// Vertices further than this from the image (in pixels) are clipped away, which bounds fixed-point
// coordinates by 2^22 and edge-function products by 2^46: far from int64 overflow.
constexpr float kGuardBandPixels = 16384.f;
constexpr int kMaxResolution = 8192;
// Below this much work a stage runs on one thread: forking and joining a team costs more than it saves
// (much more on an oversubscribed machine, where waiting threads are descheduled).
constexpr int64_t kMinParallelWork = 16384;

// Clip planes, as bits of an outcode: near, far, and the guard band on x and y.
constexpr int kPlaneCount = 6;
// Extra outcode bit: the vertex is NaN or infinite (e.g. a diverged optimization); its faces are dropped.
constexpr uint8_t kNonFinite = 1u << kPlaneCount;

struct ClipPlanes {
  float guard_x, guard_y;  // |x/w| <= guard_x keeps the pixel x within the guard band

  float distance(const Vec4f& p, int plane) const {  // >= 0 means inside
    switch (plane) {
      case 0: return p.w() + p.z();
      case 1: return p.w() - p.z();
      case 2: return guard_x * p.w() - p.x();
      case 3: return guard_x * p.w() + p.x();
      case 4: return guard_y * p.w() - p.y();
      default: return guard_y * p.w() + p.y();
    }
  }
  uint8_t outcode(const Vec4f& p) const {
    if (!p.allFinite()) return kNonFinite;
    uint8_t code = 0;
    for (int k = 0; k < kPlaneCount; ++k)
      if (!(distance(p, k) >= 0.f)) code |= uint8_t(1u << k);
    return code;
  }
};

// A vertex ready for edge setup.
struct ScreenVertex {
  int32_t x, y;  // pixel coordinates * kSubpixel
  float inv_w;   // 1 / clip w (1 for orthographic cameras)
  float depth;   // camera-space depth
};

// Marks which original face corners a screen triangle's vertices are.
enum : int32_t { kCornersIdentity = -1, kCornersSwapped = -2 };

struct ScreenTriangle {
  int32_t x[3], y[3];
  float inv_w[3];
  float depth[3];
  int32_t face;
  int32_t corners;                 // kCornersIdentity/kCornersSwapped, or index into clipped corner table
  int16_t px0, py0, px1, py1;      // pixel range that may be covered, inclusive, never empty
  bool small;                      // at most kBlockSize pixels across in x and y (vertices, not range)
};

// Barycentrics (b1, b2) w.r.t. the original face of the three vertices of a clipped sub-triangle.
using CornerBary = std::array<Vec2f, 3>;

// floor(x + 0.5) without a libm call (no SSE4.1 rounding instructions in the baseline ISA).
int32_t round_to_int(double x) {
  const double y = x + 0.5;
  const int64_t t = int64_t(y);  // truncates toward zero
  return int32_t(t - (double(t) > y));
}

ScreenVertex to_screen(const Vec4f& clip, float depth, int width, int height) {
  // Double precision so shared vertices snap identically whichever path (plain or clipped) sees them.
  double inv_w = 1.0 / double(clip.w());
  double px = (double(clip.x()) * inv_w + 1.0) * 0.5 * width;
  double py = (1.0 - double(clip.y()) * inv_w) * 0.5 * height;
  return {round_to_int(px * kSubpixel), round_to_int(py * kSubpixel), float(inv_w), depth};
}

int64_t floor_div_subpixel(int64_t v) { return v >> kSubpixelBits; }  // arithmetic shift = floor
int64_t ceil_div_subpixel(int64_t v) { return -((-v) >> kSubpixelBits); }

// Orients the triangle so its interior has positive edge functions, applies culling and computes
// the covered pixel range. Returns false when the triangle covers no pixel centre.
bool setup_triangle(const ScreenVertex* v, int32_t face, int32_t corners, int width, int height, bool cull,
                    ScreenTriangle& t, bool* swapped) {
  int64_t area = int64_t(v[1].x - v[0].x) * (v[2].y - v[0].y) - int64_t(v[1].y - v[0].y) * (v[2].x - v[0].x);
  if (area == 0) return false;
  // Pixel y points down, so a counter-clockwise (front-facing) triangle has negative area here.
  bool front = area < 0;
  if (cull && !front) return false;
  const int order[3] = {0, front ? 2 : 1, front ? 1 : 2};
  int64_t min_x = std::min({v[0].x, v[1].x, v[2].x}), max_x = std::max({v[0].x, v[1].x, v[2].x});
  int64_t min_y = std::min({v[0].y, v[1].y, v[2].y}), max_y = std::max({v[0].y, v[1].y, v[2].y});
  int64_t px0 = std::max<int64_t>(0, ceil_div_subpixel(min_x - kHalfPixel));
  int64_t px1 = std::min<int64_t>(width - 1, floor_div_subpixel(max_x - kHalfPixel));
  int64_t py0 = std::max<int64_t>(0, ceil_div_subpixel(min_y - kHalfPixel));
  int64_t py1 = std::min<int64_t>(height - 1, floor_div_subpixel(max_y - kHalfPixel));
  if (px0 > px1 || py0 > py1) return false;
  for (int k = 0; k < 3; ++k) {
    const ScreenVertex& s = v[order[k]];
    t.x[k] = s.x;
    t.y[k] = s.y;
    t.inv_w[k] = s.inv_w;
    t.depth[k] = s.depth;
  }
  t.face = face;
  t.corners = corners == kCornersIdentity && front ? kCornersSwapped : corners;
  t.small = max_x - min_x <= kBlockSize * kSubpixel && max_y - min_y <= kBlockSize * kSubpixel;
  t.px0 = int16_t(px0);
  t.px1 = int16_t(px1);
  t.py0 = int16_t(py0);
  t.py1 = int16_t(py1);
  if (swapped) *swapped = front;
  return true;
}

struct ClipVertex {
  Vec4f clip;
  float depth;
  Vec2f bary;  // (b1, b2) within the original face
};

// Sutherland-Hodgman clipping of one face against the planes its vertices violate, then fan
// triangulation. Appends screen triangles and their corner barycentrics.
void clip_face(const std::array<ClipVertex, 3>& face_vertices, uint8_t planes_hit, const ClipPlanes& planes,
               int32_t face, int width, int height, bool cull, std::vector<ScreenTriangle>& out,
               std::vector<CornerBary>& corners_out) {
  constexpr int kMaxVertices = 3 + kPlaneCount;
  std::array<ClipVertex, kMaxVertices> a, b;
  int n = 3;
  std::copy(face_vertices.begin(), face_vertices.end(), a.begin());
  for (int plane = 0; plane < kPlaneCount && n >= 3; ++plane) {
    if (!(planes_hit & (1u << plane))) continue;
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const ClipVertex& p = a[i];
      const ClipVertex& q = a[(i + 1) % n];
      float dp = planes.distance(p.clip, plane), dq = planes.distance(q.clip, plane);
      bool p_in = dp >= 0.f, q_in = dq >= 0.f;
      if (p_in) b[m++] = p;
      if (p_in != q_in) {
        // Interpolate from the inside vertex so both faces sharing this edge compute the same point.
        const ClipVertex& in = p_in ? p : q;
        const ClipVertex& outside = p_in ? q : p;
        float d_in = p_in ? dp : dq, d_out = p_in ? dq : dp;
        float s = d_in / (d_in - d_out);
        b[m++] = {in.clip + s * (outside.clip - in.clip), in.depth + s * (outside.depth - in.depth),
                  in.bary + s * (outside.bary - in.bary)};
      }
    }
    n = m;
    std::swap(a, b);
  }
  if (n < 3) return;
  std::array<ScreenVertex, kMaxVertices> screen;
  for (int i = 0; i < n; ++i) screen[i] = to_screen(a[i].clip, a[i].depth, width, height);
  for (int i = 1; i + 1 < n; ++i) {
    ScreenVertex tri[3] = {screen[0], screen[i], screen[i + 1]};
    ScreenTriangle t;
    bool swapped = false;
    int32_t corner_index = int32_t(corners_out.size());  // chunk-local; made global after the merge
    if (!setup_triangle(tri, face, corner_index, width, height, cull, t, &swapped)) continue;
    CornerBary c = {a[0].bary, a[i].bary, a[i + 1].bary};
    if (swapped) std::swap(c[1], c[2]);
    corners_out.push_back(c);
    out.push_back(t);
  }
}

#if defined(__SSE2__)  // every x86-64 CPU; elsewhere small triangles take the scalar narrow path
// Shades the covered pixels of a block of (rows + 1) x (4 * kVectors) pixels starting at (xs, ys),
// columns 0..span, given the edge functions at its first pixel (`row`) and their steps.
template <int kVectors, typename Shade>
inline void draw_block(const int64_t* row, const int64_t* step_x, const int64_t* step_y, int xs, int ys, int span,
                       int rows, int width, Shade&& shade) {
  constexpr int kColumns = 4 * kVectors;
  __m128i e[3][kVectors], dy[3];
  for (int k = 0; k < 3; ++k) {
    const int32_t base = int32_t(row[k]), sx = int32_t(step_x[k]);
    for (int v = 0; v < kVectors; ++v) {
      const int32_t first = base + 4 * v * sx;
      e[k][v] = _mm_setr_epi32(first, first + sx, first + 2 * sx, first + 3 * sx);
    }
    dy[k] = _mm_set1_epi32(int32_t(step_y[k]));
  }
  alignas(16) int32_t values[kBlockSize][3][kColumns];  // [row][edge][column]
  const uint64_t columns = (uint64_t(1) << (span + 1)) - 1;
  uint64_t inside = 0;  // bit j * 8 + i: pixel (xs + i, ys + j)
  for (int j = 0; j <= rows; ++j) {
    uint64_t outside = 0;
    for (int v = 0; v < kVectors; ++v) {
      const __m128i any_negative = _mm_or_si128(_mm_or_si128(e[0][v], e[1][v]), e[2][v]);
      outside |= uint64_t(_mm_movemask_ps(_mm_castsi128_ps(any_negative))) << (4 * v);
      for (int k = 0; k < 3; ++k) {
        _mm_store_si128(reinterpret_cast<__m128i*>(values[j][k] + 4 * v), e[k][v]);
        e[k][v] = _mm_add_epi32(e[k][v], dy[k]);
      }
    }
    inside |= (~outside & columns) << (8 * j);
  }
  while (inside != 0) {
    const int bit = __builtin_ctzll(inside);
    inside &= inside - 1;
    const int i = bit & 7, j = bit >> 3;
    shade(size_t(ys + j) * width + size_t(xs + i), values[j][0][i], values[j][1][i], values[j][2][i]);
  }
}
#endif

// Draws one triangle into the pixels of a tile (pixel rectangle [x0,x1] x [y0,y1]).
inline void draw_in_tile(const ScreenTriangle& t, const CornerBary* clipped_corners, int x0, int y0, int x1, int y1,
                         RasterBuffer& buf) {
  int xs = std::max<int>(t.px0, x0), xe = std::min<int>(t.px1, x1);
  int ys = std::max<int>(t.py0, y0), ye = std::min<int>(t.py1, y1);
  if (xs > xe || ys > ye) return;
  // Edge k is opposite vertex k and runs from vertex k+1 to vertex k+2; inside means e_k > 0, or
  // e_k == 0 on a top or left edge (bias 0), so exactly one of two triangles sharing an edge owns it.
  int64_t step_x[3], step_y[3], row[3], bias[3];
  const int64_t cx = int64_t(xs) * kSubpixel + kHalfPixel, cy = int64_t(ys) * kSubpixel + kHalfPixel;
  for (int k = 0; k < 3; ++k) {
    int a = (k + 1) % 3, b = (k + 2) % 3;
    int64_t dx = int64_t(t.x[b]) - t.x[a], dy = int64_t(t.y[b]) - t.y[a];
    bool top_left = dy < 0 || (dy == 0 && dx > 0);
    bias[k] = top_left ? 0 : 1;
    step_x[k] = -dy * kSubpixel;
    step_y[k] = dx * kSubpixel;
    row[k] = dx * (cy - t.y[a]) - dy * (cx - t.x[a]) - bias[k];
  }
  const int width = buf.width;
  float* depth = buf.depth.data();
  int32_t* face_id = buf.face_id.data();
  Vec2f* bary = buf.bary.data();
  const float iw0 = t.inv_w[0], iw1 = t.inv_w[1], iw2 = t.inv_w[2];
  const float d0 = t.depth[0], d1 = t.depth[1], d2 = t.depth[2];
  const float bias0 = float(bias[0]), bias1 = float(bias[1]), bias2 = float(bias[2]);
  // Depth test and write of one covered pixel, given its (biased) edge functions.
  auto shade = [&](size_t idx, int64_t e0, int64_t e1, int64_t e2) {
    // Screen-space weights divided by w give the perspective-correct (3D) barycentrics.
    const float q0 = (float(e0) + bias0) * iw0, q1 = (float(e1) + bias1) * iw1, q2 = (float(e2) + bias2) * iw2;
    const float inv_sum = 1.f / (q0 + q1 + q2);
    const float z = (q0 * d0 + q1 * d1 + q2 * d2) * inv_sum;
    if (z < depth[idx] || (z == depth[idx] && t.face < face_id[idx])) {
      depth[idx] = z;
      face_id[idx] = t.face;
      const float b0 = q0 * inv_sum, b1 = q1 * inv_sum, b2 = q2 * inv_sum;
      if (t.corners == kCornersIdentity) {
        bary[idx] = Vec2f(b1, b2);
      } else if (t.corners == kCornersSwapped) {
        bary[idx] = Vec2f(b2, b1);
      } else {
        const CornerBary& c = clipped_corners[t.corners];
        bary[idx] = b0 * c[0] + b1 * c[1] + b2 * c[2];
      }
    }
  };
  const int span_max = xe - xs;
#if defined(__SSE2__)
  if (t.small && span_max < kBlockSize && ye - ys < kBlockSize) {
    // Small (most triangles of a finely remeshed surface): all at most 8x8 pixels are tested at once,
    // four per SSE2 compare, into a bit mask whose set bits are then shaded. The scalar loops below
    // branch on every pixel's inside test, a coin flip the CPU mispredicts about every other pixel.
    // The triangle itself spans at most 8 pixels (not just its part in this tile), so every edge
    // function here is below 2^24 in magnitude: 32-bit lanes are exact and give the same signs as the
    // 64-bit values, which `shade` receives.
    if (span_max < 4)
      draw_block<1>(row, step_x, step_y, xs, ys, span_max, ye - ys, width, shade);
    else
      draw_block<2>(row, step_x, step_y, xs, ys, span_max, ye - ys, width, shade);
    return;
  }
#endif
  if (span_max < kNarrowSpan) {  // narrow: testing every pixel is cheaper than solving for the span
    for (int y = ys; y <= ye; ++y, row[0] += step_y[0], row[1] += step_y[1], row[2] += step_y[2]) {
      int64_t e0 = row[0], e1 = row[1], e2 = row[2];
      size_t idx = size_t(y) * width + xs;
      for (int x = xs; x <= xe; ++x, ++idx, e0 += step_x[0], e1 += step_x[1], e2 += step_x[2])
        if ((e0 | e1 | e2) >= 0) shade(idx, e0, e1, e2);
    }
    return;
  }
  // Wide: per row the covered pixels form one interval (the triangle is convex). Reciprocals of the
  // steps give a guess of its ends, exact integer tests settle them.
  double inv_step[3];
  for (int k = 0; k < 3; ++k) inv_step[k] = step_x[k] != 0 ? 1.0 / double(step_x[k]) : 0.0;
  for (int y = ys; y <= ye; ++y, row[0] += step_y[0], row[1] += step_y[1], row[2] += step_y[2]) {
    int64_t lo = 0, hi = span_max;  // pixel offsets from xs, inclusive
    for (int k = 0; k < 3 && lo <= hi; ++k) {
      const int64_t e = row[k], sx = step_x[k];
      if (sx == 0) {
        if (e < 0) hi = -1;
      } else if (sx > 0) {  // inside for i >= -e / sx
        if (e >= 0) continue;
        int64_t i = int64_t(std::ceil(double(-e) * inv_step[k]));
        while (i > 0 && e + sx * (i - 1) >= 0) --i;
        while (e + sx * i < 0) ++i;
        lo = std::max(lo, i);
      } else {  // inside for i <= e / -sx
        if (e < 0) {
          hi = -1;
          continue;
        }
        int64_t i = int64_t(std::floor(double(e) * -inv_step[k]));
        while (e + sx * (i + 1) >= 0) ++i;
        while (i >= 0 && e + sx * i < 0) --i;
        hi = std::min(hi, i);
      }
    }
    if (lo > hi) continue;
    int64_t e0 = row[0] + step_x[0] * lo, e1 = row[1] + step_x[1] * lo, e2 = row[2] + step_x[2] * lo;
    size_t idx = size_t(y) * width + size_t(xs + lo);
    for (int64_t i = lo; i <= hi; ++i, ++idx, e0 += step_x[0], e1 += step_x[1], e2 += step_x[2]) shade(idx, e0, e1, e2);
  }
}

}  // namespace

namespace {

// Working storage of one rasterize_into call. Each calling thread keeps its own between calls, so
// rendering frame after frame allocates (and page-faults) nothing: freeing these megabytes every
// frame cost more than a tenth of the optimisation loop's time in malloc, memset and page faults.
// The price is that a thread keeps the storage of the largest mesh it has drawn (64 bytes a face).
struct RasterScratch {
  std::vector<uint8_t> outcode;
  std::vector<ScreenVertex> screen;
  std::vector<ScreenTriangle> tris;  // chunk c's triangles compacted at the start of its face range
  std::vector<int64_t> chunk_size;
  std::vector<std::vector<ScreenTriangle>> clipped;
  std::vector<std::vector<CornerBary>> clipped_corners;
  std::vector<ScreenTriangle> extra;
  std::vector<CornerBary> corners;
  std::vector<int64_t> extra_begin;
  std::vector<uint32_t> counts;
  std::vector<PixelRect> chunk_rect;
  std::vector<size_t> tile_start;
  std::vector<size_t> cursor;
  std::vector<int32_t> bins;
};

void reset_to_background(RasterBuffer& buf, int width, int height) {
  if (buf.width != width || buf.height != height) {
    buf.width = width;
    buf.height = height;
    const size_t pixels = buf.pixel_count();
    buf.face_id.assign(pixels, -1);
    buf.bary.assign(pixels, Vec2f(0.f, 0.f));
    buf.depth.assign(pixels, std::numeric_limits<float>::infinity());
  } else if (!buf.footprint.empty()) {
    const PixelRect& r = buf.footprint;
    const size_t n = size_t(r.x1 - r.x0 + 1);
    for (int y = r.y0; y <= r.y1; ++y) {
      const size_t row = size_t(y) * width + r.x0;
      std::fill_n(buf.face_id.begin() + row, n, -1);
      std::fill_n(buf.bary.begin() + row, n, Vec2f(0.f, 0.f));
      std::fill_n(buf.depth.begin() + row, n, std::numeric_limits<float>::infinity());
    }
  }
  buf.footprint = PixelRect{};
}

}  // namespace

RasterBuffer rasterize(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces, const Camera& camera,
                       const RasterOptions& options) {
  RasterBuffer buf;
  rasterize_into(positions, faces, camera, buf, options);
  return buf;
}

void rasterize_into(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces, const Camera& camera,
                    RasterBuffer& buf, const RasterOptions& options) {
  const int width = camera.width, height = camera.height;
  require(width > 0 && height > 0, "rasterize: camera resolution must be positive");
  require(width <= kMaxResolution && height <= kMaxResolution,
          "rasterize: resolution " + std::to_string(width) + "x" + std::to_string(height) + " exceeds the maximum " +
              std::to_string(kMaxResolution));
  require(faces.size() < size_t(std::numeric_limits<int32_t>::max()), "rasterize: too many faces");

  const ClipPlanes planes{2.f * kGuardBandPixels / float(width) - 1.f, 2.f * kGuardBandPixels / float(height) - 1.f};
  const Eigen::Matrix4f world_to_clip = camera.projection * camera.world_to_camera;
  const Eigen::RowVector4f depth_row = -camera.world_to_camera.row(2);

  const int64_t nv = int64_t(positions.size()), nf = int64_t(faces.size());
  int64_t first_bad_face = nf;  // checked up front: exceptions must not leave OpenMP regions
#pragma omp parallel for reduction(min : first_bad_face) if (nf > kMinParallelWork)
  for (int64_t f = 0; f < nf; ++f)
    if ((faces[f].array() < 0).any() || (faces[f].array() >= nv).any()) first_bad_face = std::min(first_bad_face, f);
  require(first_bad_face == nf, "rasterize: face " + std::to_string(first_bad_face) + " references a vertex outside [0, " +
                                    std::to_string(nv) + ")");

  // 1. Vertices. Clip coordinates are recomputed (by the same function) for the rare clipped faces
  // rather than stored for all vertices.
  auto vertex_clip = [&](int64_t i) -> ClipVertex {
    const Vec4f p(positions[i].x(), positions[i].y(), positions[i].z(), 1.f);
    return {world_to_clip * p, depth_row.dot(p), Vec2f::Zero()};
  };
  thread_local RasterScratch scratch;
  // Growing a vector value-initialises only the new elements; every element read below is written first.
  std::vector<uint8_t>& outcode = scratch.outcode;
  std::vector<ScreenVertex>& screen = scratch.screen;
  outcode.resize(size_t(nv));
  screen.resize(size_t(nv));
#pragma omp parallel for schedule(static) if (nv > kMinParallelWork)
  for (int64_t i = 0; i < nv; ++i) {
    ClipVertex v = vertex_clip(i);
    outcode[i] = planes.outcode(v.clip);
    if (outcode[i] == 0) screen[i] = to_screen(v.clip, v.depth, width, height);
  }

  // 2. Faces -> screen triangles. Chunk c compacts its (at most one per face) triangles at the start
  // of its own range of `tris`, so only pages holding real triangles get touched; clipped
  // sub-triangles (up to 7 per face) go to a per-chunk overflow list.
  const int chunks = std::max(1, omp_get_max_threads());
  auto chunk_begin = [](int64_t n, int c, int count) { return n * c / count; };
  std::vector<ScreenTriangle>& tris = scratch.tris;
  tris.resize(size_t(nf));
  std::vector<int64_t>& chunk_size = scratch.chunk_size;
  chunk_size.assign(size_t(chunks), 0);
  std::vector<std::vector<ScreenTriangle>>& clipped = scratch.clipped;
  std::vector<std::vector<CornerBary>>& clipped_corners = scratch.clipped_corners;
  clipped.resize(size_t(chunks));
  clipped_corners.resize(size_t(chunks));
  for (int c = 0; c < chunks; ++c) clipped[size_t(c)].clear(), clipped_corners[size_t(c)].clear();
#pragma omp parallel if (nf > kMinParallelWork)
  {
    for (int c = omp_get_thread_num(); c < chunks; c += omp_get_num_threads()) {
      ScreenTriangle* out = tris.data() + chunk_begin(nf, c, chunks);
      int64_t n = 0;
      for (int64_t f = chunk_begin(nf, c, chunks), end = chunk_begin(nf, c + 1, chunks); f < end; ++f) {
        const Vec3i& ids = faces[f];
        const uint8_t o0 = outcode[ids[0]], o1 = outcode[ids[1]], o2 = outcode[ids[2]];
        if ((o0 | o1 | o2) & kNonFinite) continue;
        if ((o0 | o1 | o2) == 0) {
          ScreenVertex v[3] = {screen[ids[0]], screen[ids[1]], screen[ids[2]]};
          n += setup_triangle(v, int32_t(f), kCornersIdentity, width, height, options.cull_backfaces, out[n], nullptr);
        } else if ((o0 & o1 & o2) == 0) {  // partly inside: clip; wholly outside one plane: drop
          std::array<ClipVertex, 3> fv = {vertex_clip(ids[0]), vertex_clip(ids[1]), vertex_clip(ids[2])};
          fv[1].bary = Vec2f(1.f, 0.f);
          fv[2].bary = Vec2f(0.f, 1.f);
          clip_face(fv, o0 | o1 | o2, planes, int32_t(f), width, height, options.cull_backfaces, clipped[c],
                    clipped_corners[c]);
        }
      }
      chunk_size[c] = n;
    }
  }
  // Clipped triangles get indices nf, nf + 1, ... in chunk order; their corner indices become global.
  std::vector<ScreenTriangle>& extra = scratch.extra;
  std::vector<CornerBary>& corners = scratch.corners;
  std::vector<int64_t>& extra_begin = scratch.extra_begin;
  extra.clear();
  corners.clear();
  extra_begin.assign(size_t(chunks) + 1, 0);
  for (int c = 0; c < chunks; ++c) {
    extra_begin[c] = int64_t(extra.size());
    const int32_t base = int32_t(corners.size());
    for (auto& t : clipped[c]) t.corners += base;
    corners.insert(corners.end(), clipped_corners[c].begin(), clipped_corners[c].end());
    extra.insert(extra.end(), clipped[c].begin(), clipped[c].end());
  }
  extra_begin[chunks] = int64_t(extra.size());
  auto triangle = [&](int64_t index) -> const ScreenTriangle& {
    return index < nf ? tris[index] : extra[index - nf];
  };
  // Calls fn(index) for the triangles of chunk c, in a fixed order.
  auto for_each_triangle_of_chunk = [&](int c, auto&& fn) {
    for (int64_t i = chunk_begin(nf, c, chunks), end = i + chunk_size[c]; i < end; ++i) fn(i);
    for (int64_t j = extra_begin[c]; j < extra_begin[c + 1]; ++j) fn(nf + j);
  };
  int64_t triangle_count = int64_t(extra.size());
  for (int64_t n : chunk_size) triangle_count += n;

  // 3. Binning: count per (chunk, tile), prefix-sum in (tile, chunk) order, fill.
  const int tiles_x = (width + kTileSize - 1) / kTileSize, tiles_y = (height + kTileSize - 1) / kTileSize;
  const size_t tile_count = size_t(tiles_x) * tiles_y;
  std::vector<uint32_t>& counts = scratch.counts;
  counts.assign(size_t(chunks) * tile_count, 0);
  std::vector<PixelRect>& chunk_rect = scratch.chunk_rect;
  chunk_rect.assign(size_t(chunks), PixelRect{width, height, -1, -1});
  auto for_each_tile_of = [&](const ScreenTriangle& t, auto&& fn) {
    for (int ty = t.py0 >> kTileBits; ty <= (t.py1 >> kTileBits); ++ty)
      for (int tx = t.px0 >> kTileBits; tx <= (t.px1 >> kTileBits); ++tx) fn(size_t(ty) * tiles_x + tx);
  };
#pragma omp parallel if (triangle_count > kMinParallelWork)
  {
    for (int c = omp_get_thread_num(); c < chunks; c += omp_get_num_threads()) {
      uint32_t* count = counts.data() + size_t(c) * tile_count;
      PixelRect& rect = chunk_rect[c];
      for_each_triangle_of_chunk(c, [&](int64_t i) {
        const ScreenTriangle& t = triangle(i);
        rect = {std::min<int>(rect.x0, t.px0), std::min<int>(rect.y0, t.py0), std::max<int>(rect.x1, t.px1),
                std::max<int>(rect.y1, t.py1)};
        for_each_tile_of(t, [&](size_t tile) { ++count[tile]; });
      });
    }
  }
  PixelRect drawn{width, height, -1, -1};
  for (const PixelRect& r : chunk_rect)
    drawn = {std::min(drawn.x0, r.x0), std::min(drawn.y0, r.y0), std::max(drawn.x1, r.x1), std::max(drawn.y1, r.y1)};
  if (drawn.empty()) drawn = PixelRect{};
  std::vector<size_t>& tile_start = scratch.tile_start;
  std::vector<size_t>& cursor = scratch.cursor;
  tile_start.resize(tile_count + 1);
  cursor.resize(size_t(chunks) * tile_count);
  size_t total = 0;
  for (size_t tile = 0; tile < tile_count; ++tile) {
    tile_start[tile] = total;
    for (int c = 0; c < chunks; ++c) {
      cursor[size_t(c) * tile_count + tile] = total;
      total += counts[size_t(c) * tile_count + tile];
    }
  }
  tile_start[tile_count] = total;
  std::vector<int32_t>& bins = scratch.bins;
  bins.resize(total);
#pragma omp parallel if (triangle_count > kMinParallelWork)
  {
    for (int c = omp_get_thread_num(); c < chunks; c += omp_get_num_threads()) {
      size_t* cur = cursor.data() + size_t(c) * tile_count;
      for_each_triangle_of_chunk(c, [&](int64_t i) {
        for_each_tile_of(triangle(i), [&](size_t tile) { bins[cur[tile]++] = int32_t(i); });
      });
    }
  }

  // 4. Tiles.
  reset_to_background(buf, width, height);
  const size_t pixels = buf.pixel_count();
  buf.footprint = drawn;
#pragma omp parallel for schedule(dynamic, 1) if (int64_t(total) + int64_t(pixels / 64) > kMinParallelWork)
  for (int64_t tile = 0; tile < int64_t(tile_count); ++tile) {
    int x0 = int(tile % tiles_x) * kTileSize, y0 = int(tile / tiles_x) * kTileSize;
    int x1 = std::min(x0 + kTileSize, width) - 1, y1 = std::min(y0 + kTileSize, height) - 1;
    for (size_t k = tile_start[tile]; k < tile_start[tile + 1]; ++k)
      draw_in_tile(triangle(bins[k]), corners.data(), x0, y0, x1, y1, buf);
  }
}

}  // namespace u3d
