#pragma once
// A UV atlas for a closed mesh coloured from axis-aligned orthographic views: charts projected along the axes.
//
// Each face is assigned to the one of six axis directions its normal faces most (+Z front, +X right,
// -Z back, -X left: the four views; +Y top, -Y bottom, which no view sees head-on but which would
// be crushed in a side projection); labels are then smoothed (a face takes the label two or three of
// its neighbours share when it still faces that axis by more than `min_axis_cos`), and islands of
// fewer than `min_chart_faces` faces join the neighbouring label they share most edges with, when
// all their faces face its axis by more than `min_axis_cos`. Charts are the edge-connected pieces of one
// label, each projected orthographically onto its axis plane, seen from outside (so faces keep their
// counter-clockwise winding in UV and no face flips), and turned in that plane to its smallest bounding
// rectangle. A chart whose projection overlaps itself (a surface that folds over while still facing the
// axis) is cut at its median depth along the axis until no texel centre is covered twice; a chart with
// more than `sprawl_share` of the surface that fills less than 0.6 of its rectangle (a T, an
// outstretched limb), or one longer than half the atlas's side (a pole), is cut across its longer side
// at its median. Each chart is scaled by
// sqrt(surface area / projected area), so every chart has the same texels per unit of surface.
// The charts are packed, largest first, into a bitmap of the atlas (at most 1024 cells a side: 2 x 2
// texels a cell at 2048): each takes the lowest, then leftmost, place in one of four quarter turns where
// the cells it touches, grown by `gutter_texels` (rounded up to whole cells), meet no claimed cell, so
// small charts fill the bays and holes of large ones; the scale is searched from 0.92 of the scale that
// would fill the atlas down in 3 % steps until all charts fit, then bisected to 0.5 %. Texels two
// charts touch are at least `gutter_texels` apart, so bilinear lookups and mipmaps of a dilated texture
// do not bleed between charts. docs/file_formats.md compares this with xatlas-style packers.
//
// Why not Open3D's UVAtlas (t::geometry::TriangleMesh::ComputeUVAtlas): Debian's Open3D 0.16 is built
// without it (it throws "UVAtlas not available in Debian"); it is also single-threaded and rejects
// non-manifold meshes. Axis-projected charts suit colours that come from axis-aligned views, take
// about 0.4 s on 40k faces (bench/texture.cpp) and never reject a mesh.
#include <vector>

#include "core/mesh.h"

namespace u3d {

struct UvAtlasOptions {
  int texture_size = 2048;    // texels per side of the square atlas
  int gutter_texels = 4;      // empty texels around each chart
  float min_axis_cos = 0.3f;  // smoothing never gives a face an axis it faces less than this
  int min_chart_faces = 50;   // smaller islands join a neighbouring chart (if min_axis_cos allows)
  float sprawl_share = 0.0025f;  // charts with more of the surface than this are cut while they fill under 0.6 of their box
};

struct UvAtlas {
  // The input geometry with a vertex per (input vertex, chart) pair, so every vertex has one UV
  // (mesh UV convention, (0,0) = bottom-left of the texture). Vertex colours travel; materials do not.
  Mesh mesh;
  std::vector<int> source_vertex;  // per atlas vertex, the input vertex it copies
  std::vector<int> face_chart;     // per face (same order as the input), its chart
  int chart_count = 0;
  float texels_per_unit = 0.f;   // atlas texels per world unit of surface, the same in every chart (on average over it)
  float texel_efficiency = 0.f;  // the charts' triangles' area in UV over the atlas's (gutters not counted)
};

// Throws Error for an empty mesh or options out of range (texture_size < 16, gutter < 0, or a
// texture too small for the gutters of all charts).
UvAtlas axis_chart_atlas(const Mesh& mesh, const UvAtlasOptions& options = {});

}  // namespace u3d
