// Each loss term's analytic gradient w.r.t. vertex positions against central finite differences, on a
// small mesh seen by the four views, silhouette vertices included. Image terms are compared on
// perturbations that change no discrete decision (pixel coverage, anti-aliasing edge and side, the
// rendered-alpha > 0.5 selection); those must cover most coordinates and the silhouette.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "geometry/icosphere.h"
#include "gradient_check.h"
#include "isomer/normal_renderer.h"
#include "isomer/reconstruction_losses.h"
#include "shape_fixtures.h"

using namespace u3d;

namespace {

Mesh lumpy(unsigned seed, float radius) {
  Mesh m = make_icosphere(1, radius);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.85f, 1.15f);
  for (Vec3f& p : m.positions) p *= u(rng);
  return m;
}

enum class Term { Normal, BackgroundAlpha };

struct Outcome {
  double relative_error = 0;
  int compared = 0;
  int silhouette_compared = 0;
};

// Compares one image loss term, one view at a time, against a target rendered from another mesh.
Outcome check_image_term(Term term) {
  const Mesh m = lumpy(7, 0.6f);
  const Mesh target_mesh = lumpy(21, 0.55f);
  const int res = 32;
  Outcome out;
  double err2 = 0, ref2 = 0;
  for (View view : kAllViews) {
    const std::vector<Camera> cams = {view_camera(view, res)};
    const std::vector<Image> maps = test::render_normal_maps(target_mesh, cams);
    const std::vector<NormalTarget> targets = {make_normal_target(maps[0])};
    const std::vector<const Image*> refs = {&targets[0].rgba};
    NormalRenderer r(cams);
    std::vector<int64_t> decisions;
    auto loss = [&](const std::vector<Vec3f>& pos, std::vector<Vec3f>* grad) {
      const VertexNormals n = compute_vertex_normals(pos, m.faces);
      r.render(pos, m.faces, build_edge_topology(m.faces, pos.size()), n.unit);
      const DifferentiableView& v = r.view(0);
      decisions.assign(v.raster.face_id.begin(), v.raster.face_id.end());
      for (const AntialiasPair& a : v.pairs)
        decisions.push_back((int64_t(a.pixel0) << 34) + (int64_t(a.face) << 4) + (a.edge << 1) + (a.alpha > 0.f));
      for (int32_t p : v.active) decisions.push_back(v.image.data[size_t(p) * 4 + 3] > 0.5f);
      const double value = term == Term::Normal ? masked_image_l2(r, refs, 4, 1.f) : background_alpha_l2(r, targets, 1.f);
      if (grad) {
        grad->assign(pos.size(), Vec3f::Zero());
        r.backward(pos, m.faces, n, *grad);
      }
      return value;
    };
    std::vector<Vec3f> analytic;
    loss(m.positions, &analytic);
    const std::vector<int64_t> base = decisions;
    std::vector<char> silhouette(m.vertex_count(), 0);
    for (const AntialiasPair& a : r.view(0).pairs) {
      const Vec3i& f = m.faces[a.face];
      silhouette[f[(a.edge + 1) % 3]] = silhouette[f[(a.edge + 2) % 3]] = 1;
    }
    const float h = 5e-3f;  // 0.08 px: above the rasterizer's 1/256 px snapping
    for (size_t v = 0; v < m.vertex_count(); ++v)
      for (int k = 0; k < 3; ++k) {
        std::vector<Vec3f> p = m.positions;
        p[v][k] += h;
        const double up = loss(p, nullptr);
        bool stable = decisions == base;
        p[v][k] -= 2 * h;
        const double down = loss(p, nullptr);
        if (!stable || decisions != base) continue;
        const double numeric = (up - down) / (2 * h), e = analytic[v][k] - numeric;
        err2 += e * e, ref2 += numeric * numeric, ++out.compared;
        out.silhouette_compared += silhouette[v] && std::abs(analytic[v][k]) > 0.f;
      }
  }
  out.relative_error = std::sqrt(err2 / std::max(ref2, 1e-30));
  return out;
}

}  // namespace

TEST(LossGradients, MaskedNormalL2) {
  const Outcome o = check_image_term(Term::Normal);
  EXPECT_GT(o.compared, 200);
  EXPECT_GT(o.silhouette_compared, 40);
  EXPECT_LT(o.relative_error, 0.03);
}

TEST(LossGradients, BackgroundAlphaL2) {
  const Outcome o = check_image_term(Term::BackgroundAlpha);
  EXPECT_GT(o.compared, 200);
  EXPECT_GT(o.silhouette_compared, 20);
  EXPECT_LT(o.relative_error, 0.03);
}

// The expansion term's gradient is that of 0.5 * mean |c - p|^2 with c = p + n frozen (a stop-gradient),
// so it is checked against finite differences of that surrogate.
TEST(LossGradients, ExpansionPushesAlongNormals) {
  const Mesh m = lumpy(3, 0.6f);
  const VertexNormals n0 = compute_vertex_normals(m.positions, m.faces);
  std::vector<Vec3f> frozen(m.vertex_count());
  for (size_t v = 0; v < frozen.size(); ++v) frozen[v] = m.positions[v] + n0.unit[v];
  const float weight = 0.1f;
  test::LossFn surrogate = [&](const std::vector<Vec3f>& pos, std::vector<Vec3f>* grad) {
    double s = 0;
    for (size_t v = 0; v < pos.size(); ++v) s += 0.5 * (frozen[v] - pos[v]).squaredNorm();
    s *= weight / double(3 * pos.size());
    if (grad) {
      grad->assign(pos.size(), Vec3f::Zero());
      const double value = expansion_loss(n0.unit, weight, *grad);
      EXPECT_NEAR(value, s, 1e-6);
    }
    return s;
  };
  std::vector<int> all(m.vertex_count());
  for (size_t i = 0; i < all.size(); ++i) all[i] = int(i);
  const auto c = test::compare_gradients(surrogate, m.positions, all, 1e-3f);
  EXPECT_LT(c.relative_error, 1e-3);
  // Descending the gradient moves every vertex outward along its normal.
  for (size_t v = 0; v < m.vertex_count(); ++v) EXPECT_LT(c.analytic[v].dot(n0.unit[v]), 0.f);
}

TEST(LossGradients, OutOfBoxPenalty) {
  Mesh m = lumpy(5, 1.0f);  // part of it sticks out of [-0.99, 0.99]^3
  test::LossFn loss = [&](const std::vector<Vec3f>& pos, std::vector<Vec3f>* grad) {
    std::vector<Vec3f> scratch(pos.size(), Vec3f::Zero());
    const double value = out_of_box_loss(pos, 0.99f, 10.f, scratch);
    if (grad) *grad = scratch;
    return value;
  };
  std::vector<int> all(m.vertex_count());
  for (size_t i = 0; i < all.size(); ++i) all[i] = int(i);
  std::vector<Vec3f> g;
  ASSERT_GT(loss(m.positions, &g), 0.0);
  const auto c = test::compare_gradients(loss, m.positions, all, 1e-4f);
  EXPECT_LT(c.relative_error, 1e-2);
}
