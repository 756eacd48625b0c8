// Analytic gradients of the differentiable normal renderer and of every loss term against central
// finite differences, on small meshes seen by the four orthographic views and by a perspective camera.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"
#include "geometry/icosphere.h"
#include "gradient_check.h"
#include "isomer/normal_renderer.h"
#include "isomer/reconstruction_losses.h"
#include "render/barycentric_backward.h"
#include "render/interpolate.h"

using namespace u3d;
using u3d::test::compare_gradients;

namespace {

// A lumpy sphere: an icosphere with random radial noise, so normals vary and silhouettes are irregular.
Mesh lumpy_sphere(int subdivisions, float radius, unsigned seed) {
  Mesh m = make_icosphere(subdivisions, radius);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.85f, 1.15f);
  for (Vec3f& p : m.positions) p *= u(rng);
  return m;
}

// Deterministic per-pixel weights in [-1, 1].
Image random_weights(int w, int h, unsigned seed) {
  Image img(w, h, 4);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (float& x : img.data) x = u(rng);
  return img;
}

// Vertices lying on some view's silhouette: those of faces involved in anti-aliased pairs.
std::vector<int> silhouette_vertices(const NormalRenderer& r, const std::vector<Vec3i>& faces, size_t n) {
  std::vector<char> mark(n, 0);
  for (size_t i = 0; i < r.view_count(); ++i)
    for (const AntialiasPair& p : r.view(i).pairs) {
      const Vec3i& f = faces[p.face];
      mark[f[(p.edge + 1) % 3]] = mark[f[(p.edge + 2) % 3]] = 1;
    }
  std::vector<int> out;
  for (size_t v = 0; v < n; ++v)
    if (mark[v]) out.push_back(int(v));
  return out;
}

}  // namespace

// Interpolation is linear in the attributes: the backward must match exactly.
TEST(RenderGradients, InterpolateBackwardToAttributes) {
  Mesh m = lumpy_sphere(1, 0.7f, 1);
  Camera cam = view_camera(View::Front, 24);
  RasterBuffer raster = rasterize(m, cam);
  std::vector<int32_t> pixels = covered_pixels(raster);
  ASSERT_GT(pixels.size(), 100u);
  const int ch = 3;
  std::vector<float> attr(m.vertex_count() * ch);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (float& a : attr) a = u(rng);
  Image weights = random_weights(24, 24, 5);
  Image w3(24, 24, ch);
  for (size_t p = 0; p < w3.pixel_count(); ++p)
    for (int c = 0; c < ch; ++c) w3.data[p * ch + c] = weights.data[p * 4 + c];
  auto loss = [&](const std::vector<float>& a) {
    Image out(24, 24, ch);
    interpolate(raster, pixels, m.faces, a.data(), ch, out);
    double s = 0;
    for (size_t i = 0; i < out.data.size(); ++i) s += double(out.data[i]) * w3.data[i];
    return s;
  };
  std::vector<float> grad(attr.size(), 0.f);
  interpolate_backward(raster, pixels, m.faces, attr.data(), ch, w3, grad.data(), nullptr);
  for (size_t i = 0; i < attr.size(); i += 7) {
    std::vector<float> a = attr;
    a[i] += 0.5f;
    const double up = loss(a);
    a[i] -= 1.f;
    const double down = loss(a);
    EXPECT_NEAR(grad[i], (up - down) / 1.0, 1e-3) << "attribute " << i;
  }
}

// Barycentric path (no coverage change): perturbations small enough that every pixel keeps its face.
TEST(RenderGradients, BarycentricBackwardOrthographicAndPerspective) {
  Mesh m = lumpy_sphere(1, 0.7f, 2);
  const std::vector<Camera> cams = {view_camera(View::Right, 32),
                                    perspective_camera({0.8f, 0.6f, 2.5f}, 32, 32, 50.f)};
  for (const Camera& cam : cams) {
    const RasterBuffer base = rasterize(m, cam);
    const std::vector<int32_t> pixels = covered_pixels(base);
    const int ch = 3;
    std::vector<float> attr(m.vertex_count() * ch);
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (float& a : attr) a = u(rng);
    Image w(32, 32, ch);
    for (float& x : w.data) x = u(rng) - 0.5f;
    // Loss over the pixels whose face stays the same for the given rasters.
    auto loss_on = [&](const std::vector<Vec3f>& pos, const std::vector<int32_t>& px) {
      RasterBuffer r = rasterize(pos, m.faces, cam);
      Image out(32, 32, ch);
      interpolate(r, px, m.faces, attr.data(), ch, out);
      double s = 0;
      for (int32_t p : px)
        for (int c = 0; c < ch; ++c) s += double(out.data[size_t(p) * ch + c]) * w.data[size_t(p) * ch + c];
      return s;
    };
    const float h = cam.orthographic ? 1e-2f : 3e-2f;  // well above the rasterizer's 1/256 px vertex snapping
    double err2 = 0, ref2 = 0;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      for (int k = 0; k < 3; ++k) {
        std::vector<Vec3f> up = m.positions, down = m.positions;
        up[v][k] += h;
        down[v][k] -= h;
        RasterBuffer ru = rasterize(up, m.faces, cam), rd = rasterize(down, m.faces, cam);
        std::vector<int32_t> stable;
        for (int32_t p : pixels)
          if (ru.face_id[p] == base.face_id[p] && rd.face_id[p] == base.face_id[p]) stable.push_back(p);
        const double numeric = (loss_on(up, stable) - loss_on(down, stable)) / (2 * h);
        std::vector<float> ga(attr.size(), 0.f);
        std::vector<Vec2f> gb(base.pixel_count(), Vec2f::Zero());
        interpolate_backward(base, stable, m.faces, attr.data(), ch, w, ga.data(), &gb);
        ScreenProjection proj = project_to_screen(m.positions, cam);
        ScreenGradient sg;
        sg.reset(m.vertex_count());
        barycentric_backward(base, stable, m.faces, proj, gb, sg);
        std::vector<Vec3f> gp(m.vertex_count(), Vec3f::Zero());
        add_world_gradient(proj, m.positions, sg, gp);
        err2 += std::pow(gp[v][k] - numeric, 2);
        ref2 += numeric * numeric;
      }
    }
    // The rasterizer snaps vertices to 1/256 px, so finite differences carry noise ~ 1/step.
    EXPECT_LT(std::sqrt(err2 / ref2), cam.orthographic ? 0.02 : 0.06) << (cam.orthographic ? "orthographic" : "perspective");
  }
}

// The fused orthographic backward against the two separate steps it replaces. The screen gradient
// uses the same sums, so only the summation order differs; the attribute gradient uses the
// unsnapped vertices' barycentrics instead of the raster's (1/256 px snapping).
TEST(RenderGradients, FusedOrthographicBackwardMatchesTheTwoSteps) {
  const Mesh m = lumpy_sphere(3, 0.7f, 6);
  const Camera cam = view_camera(View::Right, 96);
  const RasterBuffer raster = rasterize(m.positions, m.faces, cam, RasterOptions{.cull_backfaces = true});
  const std::vector<int32_t> pixels = covered_pixels(raster);
  ASSERT_GT(pixels.size(), 2000u);
  const ScreenProjection proj = project_to_screen(m.positions, cam);
  const int ch = 4;
  std::vector<float> attr(m.vertex_count() * ch);
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (float& a : attr) a = u(rng);
  const Image grad = random_weights(96, 96, 9);

  std::vector<float> attr_two(attr.size(), 0.f), attr_fused(attr.size(), 0.f);
  std::vector<Vec2f> grad_bary(raster.pixel_count(), Vec2f::Zero());
  ScreenGradient two, fused;
  two.reset(m.vertex_count());
  fused.reset(m.vertex_count());
  interpolate_backward(raster, pixels, m.faces, attr.data(), ch, grad, attr_two.data(), &grad_bary);
  barycentric_backward(raster, pixels, m.faces, proj, grad_bary, two);
  interpolate_barycentric_backward_orthographic(raster, pixels, m.faces, attr.data(), ch, proj, grad, attr_fused.data(),
                                                fused);

  double err2 = 0, ref2 = 0;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    err2 += (two.pixel[v] - fused.pixel[v]).squaredNorm();
    ref2 += two.pixel[v].squaredNorm();
  }
  ASSERT_GT(ref2, 0.0);
  EXPECT_LT(std::sqrt(err2 / ref2), 2e-4) << "screen gradient";  // float sums of g q in another order
  err2 = ref2 = 0;
  for (size_t i = 0; i < attr.size(); ++i) {
    err2 += std::pow(double(attr_two[i]) - attr_fused[i], 2);
    ref2 += std::pow(double(attr_two[i]), 2);
  }
  ASSERT_GT(ref2, 0.0);
  EXPECT_LT(std::sqrt(err2 / ref2), 1e-2) << "attribute gradient";

  // A constant last channel (the renderer's alpha) moves nothing: leaving it out changes no result.
  for (size_t v = 0; v < m.vertex_count(); ++v) attr[v * ch + 3] = 1.f;
  std::vector<float> attr_all(attr.size(), 0.f), attr_three(attr.size(), 0.f);
  ScreenGradient all, three;
  all.reset(m.vertex_count());
  three.reset(m.vertex_count());
  interpolate_barycentric_backward_orthographic(raster, pixels, m.faces, attr.data(), 4, proj, grad, attr_all.data(), all);
  interpolate_barycentric_backward_orthographic(raster, pixels, m.faces, attr.data(), 3, proj, grad, attr_three.data(),
                                                three);
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    EXPECT_EQ(all.pixel[v], three.pixel[v]) << "vertex " << v;
    for (int c = 0; c < 3; ++c) EXPECT_EQ(attr_all[v * ch + c], attr_three[v * ch + c]) << "vertex " << v;
  }

  const Camera perspective = perspective_camera({0.8f, 0.6f, 2.5f}, 32, 32, 50.f);
  EXPECT_THROW(interpolate_barycentric_backward_orthographic(raster, pixels, m.faces, attr.data(), ch,
                                                             project_to_screen(m.positions, perspective), grad,
                                                             attr_fused.data(), fused),
               Error);
}

// The full renderer (normals + barycentrics + silhouettes) under a random linear image loss, one view
// at a time. The rasterizer's coverage is piecewise constant, so finite differences are only
// meaningful for perturbations that change no pixel's triangle and no anti-aliasing decision (which
// edge a pixel pair blends across, which of the two pixels it changes): those are compared, and must be plentiful, on silhouette vertices too.
TEST(RenderGradients, NormalRendererMatchesFiniteDifferences) {
  Mesh m = lumpy_sphere(1, 0.6f, 7);
  const int res = 32;
  double err2 = 0, ref2 = 0, sil_err2 = 0, sil_ref2 = 0;
  int compared = 0, sil_compared = 0;
  for (View view : kAllViews) {
    NormalRenderer renderer({view_camera(view, res)});
    const Image weights = random_weights(res, res, 11 + int(view));
    std::vector<int64_t> face_ids;  // raster face ids, then the blended pairs' (pixel, face, edge)
    auto loss = [&](const std::vector<Vec3f>& pos, std::vector<Vec3f>* grad) {
      VertexNormals n = compute_vertex_normals(pos, m.faces);
      renderer.render(pos, m.faces, build_edge_topology(m.faces, pos.size()), n.unit);
      DifferentiableView& v = renderer.view(0);
      face_ids.assign(v.raster.face_id.begin(), v.raster.face_id.end());
      for (const AntialiasPair& a : v.pairs) face_ids.push_back((int64_t(a.pixel0) << 34) + (int64_t(a.face) << 4) + (a.edge << 1) + (a.alpha > 0.f));
      double s = 0;
      for (int32_t p : v.active)
        for (int c = 0; c < 4; ++c) {
          s += double(v.image.data[size_t(p) * 4 + c]) * weights.data[size_t(p) * 4 + c];
          v.grad_image.data[size_t(p) * 4 + c] = weights.data[size_t(p) * 4 + c];
        }
      if (grad) {
        grad->assign(pos.size(), Vec3f::Zero());
        renderer.backward(pos, m.faces, n, *grad);
      }
      return s;
    };
    std::vector<Vec3f> analytic;
    loss(m.positions, &analytic);
    const std::vector<int64_t> base_ids = face_ids;
    const std::vector<int> sil = silhouette_vertices(renderer, m.faces, m.vertex_count());
    const float h = 5e-3f;  // 0.08 px: above the rasterizer's 1/256 px snapping
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      const bool on_silhouette = std::find(sil.begin(), sil.end(), int(v)) != sil.end();
      for (int k = 0; k < 3; ++k) {
        std::vector<Vec3f> p = m.positions;
        p[v][k] += h;
        const double up = loss(p, nullptr);
        bool stable = face_ids == base_ids;
        p[v][k] -= 2 * h;
        const double down = loss(p, nullptr);
        stable = stable && face_ids == base_ids;
        if (!stable) continue;
        const double numeric = (up - down) / (2 * h), e = analytic[v][k] - numeric;
        err2 += e * e, ref2 += numeric * numeric, ++compared;
        if (on_silhouette) sil_err2 += e * e, sil_ref2 += numeric * numeric, ++sil_compared;
      }
    }
  }
  EXPECT_GT(compared, 200);
  EXPECT_GT(sil_compared, 40);
  EXPECT_LT(std::sqrt(err2 / ref2), 0.03);
  EXPECT_LT(std::sqrt(sil_err2 / sil_ref2), 0.03);
}
