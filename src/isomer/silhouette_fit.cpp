#include "isomer/silhouette_fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/disjoint_sets.h"
#include "geometry/grid_components.h"
#include "geometry/mesh_topology.h"
#include "geometry/quadric_decimation.h"
#include "geometry/signed_distance.h"
#include "isomer/silhouette_check.h"
#include "isomer/visual_hull.h"
#include "render/rasterizer.h"

namespace u3d {
namespace {

// A column counts as explained by the carved hull when at least this many of its samples are inside.
// One sample is a sliver: its surface covers a fraction of the column's pixel, and a plate 2 % of the
// object thick spans 3.5 samples at 192^3.
constexpr int kMinCoverSamples = 2;

// The local fit repairs the surface within this many samples (Chebyshev distance) of a sample where the
// masks contradict it, blended linearly into the surface's own field over that band.
constexpr int kLocalBand = 4;
// The masks contradict the surface at a sample inside it that lies at least kOutsideMargin outside a
// mask, and at a sample outside it that lies at least kInsideMargin inside every mask on the ray of a
// mask pixel it leaves uncovered (field units, 0.5 per voxel; a voxel is two pixels of views at twice
// the grid's resolution). Every optimised mesh is a pixel off its masks somewhere along its outline; that
// is no contradiction. A part is restored from the hull along the whole ray, as deep as the other masks
// allow, so only a part the mesh lacks by more than a sliver is: restoring every pixel the mesh missed
// by two or three (suzanne's outline) made suzanne 74 % worse in CD-L1 (docs/evaluation.md).
constexpr float kOutsideMargin = 0.5f;
constexpr float kInsideMargin = 1.f;

// An initial mesh with more pieces than the masks' hull is joined where its pieces come within
// kJoinGap samples (Chebyshev, on the pieces grid) of each other: a grey-scale closing by a cube of that
// radius, used within kJoinZone samples of such a gap (elsewhere the mesh's own field). Screened Poisson
// cut spot's horns and ears off the head and human_man's hands off the wrists by a sample or two at
// 64^3. A closing everywhere also fills every concavity narrower than the cube, which made human_man 7 %
// worse in CD-L1 (radius 2) and the bundled example 0.14 dB worse in PSNR (radius 3).
constexpr int kJoinGap = 2;
constexpr int kJoinZone = 4;

// What a view shows of the mesh: the depth of its nearest surface at every pixel, and the pixels of
// the mask it leaves uncovered (a part the mesh lacks).
struct DepthView {
  Camera camera;
  RasterBuffer raster;
  const Image* mask = nullptr;

  // The pixel `world` projects to, or -1 outside the image; `depth` its depth along the view.
  int64_t pixel_of(const Vec3f& world, float& depth) const {
    const Vec3f p = camera.to_pixel(world);
    depth = p.z();
    const int x = int(std::floor(p.x())), y = int(std::floor(p.y()));
    if (x < 0 || y < 0 || x >= raster.width || y >= raster.height) return -1;
    return int64_t(y) * raster.width + x;
  }
  bool unexplained(int64_t pixel) const {
    return pixel >= 0 && !raster.covered(size_t(pixel)) && is_foreground(mask->data[size_t(pixel) * 4 + 3]);
  }
  // How far a point of depth `depth` lies behind the surface seen through `pixel` (negative in front
  // of it; +inf where the pixel sees no surface).
  float behind(int64_t pixel, float depth) const {
    if (pixel < 0 || !raster.covered(size_t(pixel))) return std::numeric_limits<float>::infinity();
    return depth - raster.depth[size_t(pixel)];
  }
};

// The surface of the masks' hull field, decimated to `target_faces`.
// What each of the four views shows of `mesh`.
std::vector<DepthView> depth_views(const Mesh& mesh, const ViewSet& views) {
  std::vector<DepthView> depths;
  for (View v : kAllViews) {
    const Camera camera = view_camera(v, views[v].normals.width);
    depths.push_back({camera, rasterize(mesh, camera), &views[v].normals});
  }
  return depths;
}

Mesh hull_surface(const ScalarGrid& hull, size_t target_faces) {
  Mesh surface = extract_zero_surface(hull);
  require(!surface.faces.empty(), "silhouette fit: the four masks share no volume");
  return surface.face_count() <= target_faces ? surface : decimate_closed_mesh(surface, target_faces);
}

void check_fit_arguments(int resolution, size_t target_faces) {
  require(resolution >= 4 && resolution <= 1024,
          "silhouette fit: resolution " + std::to_string(resolution) + " is outside [4, 1024]");
  require(target_faces >= 100, "silhouette fit: the target face count must be at least 100");
}

// The surface of a fitted field, decimated to `target_faces`.
Mesh fitted_surface(const ScalarGrid& field, size_t target_faces) {
  StageTimer surface_timer("silhouette fit: surface");
  Mesh surface = extract_zero_surface(field);
  require(!surface.faces.empty(), "silhouette fit: the four masks share no volume");
  surface_timer.finish();
  if (surface.face_count() <= target_faces) return surface;
  StageTimer decimate_timer("silhouette fit: decimating " + std::to_string(surface.face_count()) + " faces");
  return decimate_closed_mesh(surface, target_faces);
}

// A separable filter of an n^3 grid, one axis at a time: each sample becomes the fold, by
// combine(best, value, offset), of the samples within `reach` of it along the axis, starting from its own.
template <typename T, typename Combine>
void filter_along_axes(std::vector<T>& values, int n, int reach, Combine combine) {
  std::vector<T> next(values.size());
  const size_t stride[3] = {1, size_t(n), size_t(n) * size_t(n)};
  for (int axis = 0; axis < 3; ++axis) {
    const size_t across_a = stride[axis == 0 ? 1 : 0], across_b = stride[axis == 2 ? 1 : 2];
#pragma omp parallel for schedule(static)
    for (int line = 0; line < n * n; ++line) {
      const size_t base = size_t(line % n) * across_a + size_t(line / n) * across_b;
      for (int i = 0; i < n; ++i) {
        T best = values[base + size_t(i) * stride[axis]];
        for (int j = std::max(0, i - reach); j <= std::min(n - 1, i + reach); ++j)
          best = combine(best, values[base + size_t(j) * stride[axis]], std::abs(i - j));
        next[base + size_t(i) * stride[axis]] = best;
      }
    }
    values.swap(next);
  }
}

// The Chebyshev distance (in samples) of every sample of an n^3 grid to the nearest marked one, capped
// at `cap`.
std::vector<uint8_t> chebyshev_distance(const std::vector<uint8_t>& marked, int n, int cap) {
  std::vector<uint8_t> distance(marked.size());
  for (size_t i = 0; i < marked.size(); ++i) distance[i] = marked[i] ? 0 : uint8_t(cap);
  filter_along_axes(distance, n, cap - 1, [](uint8_t best, uint8_t value, int offset) {
    return uint8_t(std::min(int(best), std::max(offset, int(value))));
  });
  return distance;
}

// Grey-scale dilation (take_max) or erosion of an n^3 grid by a cube of radius r.
void cube_filter(std::vector<float>& values, int n, int r, bool take_max) {
  filter_along_axes(values, n, r, [take_max](float best, float value, int) {
    return take_max ? std::max(best, value) : std::min(best, value);
  });
}

// The initial mesh's signed distance on the hull's grid, its pieces joined across the gaps between them
// (kJoinGap, kJoinZone), and cut by the masks' hull: what lies outside a mask (a band across a gap the
// masks show open) goes. Same units as the hull (0.5 per voxel).
ScalarGrid joined_and_cut_field(const Mesh& initial, const ScalarGrid& hull) {
  const int n = hull.nx;  // the grid is a cube
  const float to_field = 0.5f / hull.spacing;
  ScalarGrid own = hull;
  sample_signed_distance(initial, 1.f / to_field, own);
  for (float& value : own.values) value *= to_field;
  int pieces = 0;
  const std::vector<int> piece = label_inside_components(own, &pieces);
  // The gaps: samples within kJoinGap of two pieces or more.
  std::vector<uint8_t> near_pieces(piece.size(), 0), marked(piece.size());
  for (int p = 0; p < pieces; ++p) {
    for (size_t i = 0; i < piece.size(); ++i) marked[i] = piece[i] == p;
    const std::vector<uint8_t> distance = chebyshev_distance(marked, n, kJoinGap + 1);
    for (size_t i = 0; i < piece.size(); ++i)
      near_pieces[i] = uint8_t(std::min(near_pieces[i] + (distance[i] <= kJoinGap), 2));
  }
  for (size_t i = 0; i < piece.size(); ++i) marked[i] = near_pieces[i] == 2;
  const std::vector<uint8_t> from_gap = chebyshev_distance(marked, n, kJoinZone + 1);
  std::vector<float> closed = own.values;
  cube_filter(closed, n, kJoinGap, true);
  cube_filter(closed, n, kJoinGap, false);
  ScalarGrid field = hull;
  for (size_t i = 0; i < field.values.size(); ++i)
    field.values[i] = std::min(from_gap[i] <= kJoinZone ? closed[i] : own.values[i], hull.values[i]);
  return field;
}

}  // namespace

void drop_pieces_no_view_needs(Mesh& mesh, const ViewSet& views) {
  DisjointSets sets(mesh.positions.size());
  for (const Vec3i& f : mesh.faces) sets.unite(f[1], f[0]), sets.unite(f[2], f[0]);
  std::vector<int> piece_of_root(mesh.positions.size(), -1), face_piece(mesh.faces.size());
  int pieces = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    int& piece = piece_of_root[size_t(sets.find(mesh.faces[f][0]))];
    if (piece < 0) piece = pieces++;
    face_piece[f] = piece;
  }
  if (pieces <= 1) return;
  std::vector<uint8_t> needed(size_t(pieces), 0);
  for (View v : kAllViews) {
    const Camera camera = view_camera(v, views[v].normals.width);
    std::vector<std::vector<size_t>> covered(static_cast<size_t>(pieces));
    std::vector<uint8_t> count(size_t(camera.width) * size_t(camera.height), 0);
    for (int p = 0; p < pieces; ++p) {
      std::vector<Vec3i> faces;
      for (size_t f = 0; f < mesh.faces.size(); ++f)
        if (face_piece[f] == p) faces.push_back(mesh.faces[f]);
      const RasterBuffer raster = rasterize(mesh.positions, faces, camera);
      for (size_t i = 0; i < raster.pixel_count(); ++i)
        if (raster.covered(i)) covered[size_t(p)].push_back(i), count[i] = uint8_t(std::min(count[i] + 1, 2));
    }
    for (int p = 0; p < pieces; ++p)
      for (size_t i : covered[size_t(p)]) needed[size_t(p)] = needed[size_t(p)] || count[i] == 1;
  }
  std::vector<Vec3i> kept;
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (needed[size_t(face_piece[f])]) kept.push_back(mesh.faces[f]);
  std::vector<int> index(mesh.positions.size(), -1);
  for (const Vec3i& f : kept)
    for (int k = 0; k < 3; ++k) index[size_t(f[k])] = 0;
  std::vector<Vec3f> positions;
  for (size_t v = 0; v < index.size(); ++v)
    if (index[v] == 0) index[v] = int(positions.size()), positions.push_back(mesh.positions[v]);
  for (Vec3i& f : kept)
    for (int k = 0; k < 3; ++k) f[k] = index[size_t(f[k])];
  mesh.positions = std::move(positions);
  mesh.faces = std::move(kept);
}

ScalarGrid silhouette_fit_field(const Mesh& mesh, const ViewSet& views, int resolution) {
  const ScalarGrid hull = visual_hull_field(views, resolution, HullMasks::Normals);
  const std::vector<DepthView> depths = depth_views(mesh, views);
  const float to_field = 0.5f / hull.spacing;  // world lengths in the hull's units (0.5 per voxel)
  const int n = hull.nx;                       // the grid is a cube
  ScalarGrid field = hull;
#pragma omp parallel for schedule(dynamic)
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const size_t i = hull.index(x, y, z);
        if (hull.values[i] <= 0.f) continue;  // outside a mask: the hull's value places the surface
        const Vec3f p = hull.position(x, y, z);
        std::array<int64_t, 4> pixels;
        std::array<float, 4> sample_depths;
        bool keep = false;  // on the ray of a mask pixel the mesh leaves uncovered: no view carves it
        for (size_t v = 0; v < depths.size(); ++v) {
          pixels[v] = depths[v].pixel_of(p, sample_depths[v]);
          keep = keep || depths[v].unexplained(pixels[v]);
        }
        if (keep) continue;
        float value = hull.values[i];
        for (size_t v = 0; v < depths.size(); ++v)
          value = std::min(value, depths[v].behind(pixels[v], sample_depths[v]) * to_field);
        field.values[i] = std::max(value, -1.f);
      }
  // Per column: does the hull reach into it, and does the carved field hold at least two samples of
  // it? A column the carving emptied (the mesh misses part of a mask there) is taken from the hull.
  std::vector<uint8_t> reach_z(size_t(n) * n, 0), reach_x(reach_z.size(), 0);  // indexed x + n y, y + n z
  std::vector<int> cover_z(reach_z.size(), 0), cover_x(reach_x.size(), 0);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const size_t i = hull.index(x, y, z);
        if (hull.values[i] <= 0.f) continue;
        reach_z[size_t(x) + size_t(n) * y] = reach_x[size_t(y) + size_t(n) * z] = 1;
        if (field.values[i] > 0.f) ++cover_z[size_t(x) + size_t(n) * y], ++cover_x[size_t(y) + size_t(n) * z];
      }
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const size_t cz = size_t(x) + size_t(n) * y, cx = size_t(y) + size_t(n) * z;
        if ((reach_z[cz] && cover_z[cz] < kMinCoverSamples) || (reach_x[cx] && cover_x[cx] < kMinCoverSamples)) {
          const size_t i = hull.index(x, y, z);
          field.values[i] = hull.values[i];
        }
      }
  return field;
}

float min_silhouette_iou(const Mesh& mesh, const ViewSet& views) {
  const std::array<float, 4> iou = silhouette_iou(mesh, views);
  return *std::min_element(iou.begin(), iou.end());
}

std::optional<float> carved_hull_fill(const Mesh& mesh, const ViewSet& views, int resolution) {
  const MeshTopology topo = mesh_topology(mesh);
  if (!topo.watertight) return std::nullopt;
  const ScalarGrid field = silhouette_fit_field(mesh, views, resolution);
  // Each sample's share of its voxel from its value (0.5 per voxel from the surface): exact for a
  // plane, where counting the samples inside would be up to half a voxel off on every face.
  double inside = 0.0;
  for (float v : field.values) inside += std::clamp(0.5 + 2.0 * double(v), 0.0, 1.0);
  if (inside <= 0.0) return std::nullopt;
  return float(topo.volume / (inside * std::pow(double(field.spacing), 3)));
}

float normal_map_error(const Mesh& mesh, const ViewSet& views) {
  const std::vector<Vec3f> normals = face_normals(mesh.positions, mesh.faces);
  double sum = 0.0;
  size_t count = 0;
  for (View v : kAllViews) {
    const Image& map = views[v].normals;  // decoded: xyz in [-1, 1], alpha = mask
    const RasterBuffer raster = rasterize(mesh, view_camera(v, map.width));
    for (size_t p = 0; p < raster.pixel_count(); ++p) {
      if (!raster.covered(p) || !is_foreground(map.data[p * 4 + 3])) continue;
      const Vec3f n(map.data[p * 4], map.data[p * 4 + 1], map.data[p * 4 + 2]);
      const float length = n.norm();
      if (length < 1e-3f) continue;
      const float cosine = std::clamp(normals[size_t(raster.face_id[p])].dot(n) / length, -1.f, 1.f);
      sum += double(std::acos(cosine)) * (180.0 / M_PI);
      ++count;
    }
  }
  return count ? float(sum / double(count)) : 180.f;
}

Mesh silhouette_hull(const ViewSet& views, int resolution, size_t target_faces) {
  StageTimer timer("silhouette fit: the masks' hull at " + std::to_string(resolution) + "^3");
  return hull_surface(visual_hull_field(views, resolution, HullMasks::Normals), target_faces);
}

std::optional<Mesh> start_for_extra_pieces(const Mesh& initial, const ViewSet& views,
                                           const SilhouetteFitOptions& options, size_t target_faces) {
  const int pieces = mesh_topology(initial).components;
  if (pieces <= 1) return std::nullopt;  // the hull has at least one
  const ScalarGrid hull = visual_hull_field(views, options.pieces_resolution, HullMasks::Normals);
  const int hull_pieces = count_inside_components(hull);
  if (pieces <= hull_pieces) return std::nullopt;
  const ScalarGrid joined = joined_and_cut_field(initial, hull);
  const int joined_pieces = count_inside_components(joined);
  const std::string counts = "silhouette fit: the initial mesh has " + std::to_string(pieces) +
                             " pieces, the masks' hull " + std::to_string(hull_pieces);
  if (joined_pieces >= 1 && joined_pieces <= hull_pieces) {
    progress(counts + ": joined and cut by the hull, " + std::to_string(joined_pieces) + " piece(s)");
    return hull_surface(joined, target_faces);
  }
  progress(counts + ", joined " + std::to_string(joined_pieces) + ": starting from the hull");
  return hull_surface(hull, target_faces);
}

Mesh fit_to_silhouettes(const Mesh& mesh, const ViewSet& views, int resolution, size_t target_faces) {
  check_fit_arguments(resolution, target_faces);
  StageTimer field_timer("silhouette fit: " + std::to_string(resolution) + "^3 field");
  const ScalarGrid field = silhouette_fit_field(mesh, views, resolution);
  field_timer.finish();
  return fitted_surface(field, target_faces);
}

ScalarGrid local_fit_field(const Mesh& surface, const ViewSet& views, int resolution) {
  const ScalarGrid hull = visual_hull_field(views, resolution, HullMasks::Normals);
  const std::vector<DepthView> depths = depth_views(surface, views);
  const float to_field = 0.5f / hull.spacing;
  ScalarGrid field = hull;  // the same samples; clamped to +-1 in field units, as the hull
  sample_signed_distance(surface, 1.f / to_field, field);
  for (float& value : field.values) value *= to_field;
  // Per sample: is it on the ray of a mask pixel the surface leaves uncovered (a part it lacks), as far
  // inside every mask as kInsideMargin (1) or nearer the hull's surface (2); do the masks contradict
  // the surface there?
  const int n = hull.nx;
  std::vector<uint8_t> lacking(hull.values.size(), 0), contradicted(hull.values.size(), 0);
#pragma omp parallel for schedule(dynamic)
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const size_t i = hull.index(x, y, z);
        const float h = hull.values[i];
        if (h <= -kOutsideMargin) contradicted[i] = field.values[i] > 0.f;
        if (h <= 0.f) continue;
        float depth;
        bool uncovered = false;
        for (const DepthView& view : depths)
          uncovered = uncovered || view.unexplained(view.pixel_of(hull.position(x, y, z), depth));
        if (!uncovered) continue;
        lacking[i] = h >= kInsideMargin ? 1 : 2;
        contradicted[i] = lacking[i] == 1 && field.values[i] <= 0.f;
      }
  const int cap = kLocalBand + 1;
  const std::vector<uint8_t> distance = chebyshev_distance(contradicted, n, cap);
  std::vector<uint8_t> core(lacking.size());
  for (size_t i = 0; i < lacking.size(); ++i) core[i] = lacking[i] == 1;
  const std::vector<uint8_t> from_core = chebyshev_distance(core, n, 3);
  size_t contradictions = 0, near_surface = 0, kept = 0;
  for (size_t i = 0; i < field.values.size(); ++i) {
    const float own = field.values[i], h = hull.values[i];
    // The repaired surface: a lacking part (out to the hull's surface, within two samples of its core)
    // added, what lies outside a mask cut.
    const bool part = lacking[i] == 1 || (lacking[i] == 2 && from_core[i] <= 2);
    const float repaired = std::min(part ? std::max(own, h) : own, h);
    const float weight = 1.f - float(distance[i]) / float(cap);
    contradictions += contradicted[i];
    if (std::abs(own) < 1.f) ++near_surface, kept += weight == 0.f;
    field.values[i] = weight * repaired + (1.f - weight) * own;
  }
  char line[200];
  std::snprintf(line, sizeof line,
                "silhouette fit: the masks contradict the mesh at %zu samples; %.1f %% of its surface kept "
                "(repaired within %d samples of them)",
                contradictions, near_surface ? 100.0 * double(kept) / double(near_surface) : 100.0, kLocalBand);
  progress(line);
  return field;
}

Mesh fit_locally(const Mesh& surface, const ViewSet& views, int resolution, size_t target_faces) {
  check_fit_arguments(resolution, target_faces);
  StageTimer field_timer("silhouette fit: local " + std::to_string(resolution) + "^3 field");
  const ScalarGrid field = local_fit_field(surface, views, resolution);
  field_timer.finish();
  return fitted_surface(field, target_faces);
}

std::optional<Mesh> fit_optimised_mesh(const Mesh& optimised, const Mesh& smoothed, const ViewSet& views,
                                       const SilhouetteFitOptions& options) {
  const float iou = min_silhouette_iou(smoothed, views);
  const std::optional<float> fill = carved_hull_fill(optimised, views, options.check_resolution);
  char line[160];
  std::snprintf(line, sizeof line, "silhouette fit: smallest silhouette IoU %.3f, volume %s of the carved hull", iou,
                fill ? (std::to_string(int(std::lround(100.f * *fill))) + " %").c_str() : "unknown (open mesh)");
  progress(line);
  if (iou >= options.final_min_iou && (!fill || *fill >= options.min_fill)) return std::nullopt;
  const size_t faces = size_t(options.final_faces);
  Mesh hull = silhouette_hull(views, options.final_resolution, faces);
  if (fill && *fill < options.hull_below_fill) {
    progress("silhouette fit: the masks' hull (the mesh lost most of its volume)");
    return hull;
  }
  // A mesh that keeps its volume but leaves a mask is fitted locally: its smoothed surface is kept where
  // the masks agree with it (its signed distance needs a closed mesh). One that lost volume no view
  // sees (box_chair, signpost) is fitted whole: its depth is no account of the hidden parts.
  const bool local = fill && *fill >= options.min_fill && mesh_topology(smoothed).watertight;
  Mesh fitted = local ? fit_locally(smoothed, views, options.final_resolution, faces)
                      : fit_to_silhouettes(optimised, views, options.final_resolution, faces);
  const float fitted_error = normal_map_error(fitted, views), hull_error = normal_map_error(hull, views);
  std::snprintf(line, sizeof line, "silhouette fit: normal error %.2f deg fitted, %.2f deg the masks' hull",
                fitted_error, hull_error);
  progress(line);
  return hull_error < fitted_error ? std::move(hull) : std::move(fitted);
}

}  // namespace u3d
