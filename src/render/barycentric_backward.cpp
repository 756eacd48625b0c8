#include "render/barycentric_backward.h"

#include <cmath>
#include <string>

#include "core/error.h"

namespace u3d {

namespace {
// d cross(u, v) / du and / dv, with cross(u, v) = u.x v.y - u.y v.x.
inline Vec2f dcross_du(const Vec2f& v) { return {v.y(), -v.x()}; }
inline Vec2f dcross_dv(const Vec2f& u) { return {-u.y(), u.x()}; }
inline float cross2(const Vec2f& u, const Vec2f& v) { return u.x() * v.y() - u.y() * v.x(); }

// Orthographic case: b_i = E_i(q) / A with E_i affine in the pixel centre q, so a face's gradient only
// needs, per output barycentric k, G_k = sum_p g_k and Q_k = sum_p g_k q_p. Every affine expression in
// r_j = a_j - q is then evaluated in homogeneous form r_j -> a_j G_k - Q_k. Adds the face's share.
void add_face_barycentric_gradient(const Vec3i& c, const float (&G)[2], const Vec2f (&Q)[2],
                                   const ScreenProjection& projection, ScreenGradient& screen) {
  const Vec2f a[3] = {projection.pixel[c[0]], projection.pixel[c[1]], projection.pixel[c[2]]};
  const float area = cross2(a[1] - a[0], a[2] - a[0]);
  if (std::abs(area) < 1e-12f) return;
  Vec2f grad[3] = {Vec2f::Zero(), Vec2f::Zero(), Vec2f::Zero()};
  for (int k = 0; k < 2; ++k) {
    const int i = k + 1;  // output barycentric b_i (b1 or b2)
    const Vec2f r[3] = {a[0] * G[k] - Q[k], a[1] * G[k] - Q[k], a[2] * G[k] - Q[k]};  // homogeneous a_j - q
    // sum_p g E_i(q_p): E_i = cross(r_{i+1}, r_{i+2}) is affine in q, so one factor stays plain.
    const int j = (i + 1) % 3, l = (i + 2) % 3;
    const float e = cross2(a[j], a[l]) * G[k] - cross2(a[j], Q[k]) + cross2(a[l], Q[k]);
    // d E_i / d a_j = dcross_du(r_l), d E_i / d a_l = dcross_dv(r_j); d A / d a_* from the triangle.
    grad[j] += dcross_du(r[l]) / area;
    grad[l] += dcross_dv(r[j]) / area;
    // Through the area A = cross(a1 - a0, a2 - a0).
    const float scale = -e / (area * area);
    const Vec2f da1 = dcross_du(a[2] - a[0]), da2 = dcross_dv(a[1] - a[0]);
    grad[1] += scale * da1;
    grad[2] += scale * da2;
    grad[0] -= scale * (da1 + da2);
  }
  for (int j = 0; j < 3; ++j) screen.pixel[c[j]] += grad[j];
}

// Per-face sums over a face's pixels, kept per thread between calls (this runs for every view of
// every optimisation step): all entries are zero on entry, and only the faces the pixels touched are
// visited and reset again.
template <typename Moments>
struct FaceMoments {
  std::vector<Moments> moments;
  std::vector<int32_t> touched;

  Moments& at(int32_t face) {
    Moments& m = moments[size_t(face)];
    if (!m.used) touched.push_back(face), m.used = true;
    return m;
  }
  // Calls fn(face, moments) once per touched face, then clears them.
  template <typename Fn>
  void drain(Fn&& fn) {
    for (const int32_t f : touched) {
      const Moments m = moments[size_t(f)];
      moments[size_t(f)] = Moments{};
      fn(f, m);
    }
    touched.clear();
  }
};

void orthographic_backward(const RasterBuffer& raster, std::span<const int32_t> pixels,
                           const std::vector<Vec3i>& faces, const ScreenProjection& projection,
                           const std::vector<Vec2f>& grad_bary, ScreenGradient& screen) {
  struct Moments {
    float g[2] = {0.f, 0.f};
    Vec2f q[2] = {Vec2f::Zero(), Vec2f::Zero()};
    bool used = false;
  };
  thread_local FaceMoments<Moments> sums;
  if (sums.moments.size() < faces.size()) sums.moments.resize(faces.size());
  for (int32_t p : pixels) {
    const Vec2f& g = grad_bary[p];
    if (g.x() == 0.f && g.y() == 0.f) continue;
    Moments& m = sums.at(raster.face_id[p]);
    const Vec2f q(float(p % raster.width) + 0.5f, float(p / raster.width) + 0.5f);
    m.g[0] += g.x(), m.g[1] += g.y();
    m.q[0] += g.x() * q, m.q[1] += g.y() * q;
  }
  sums.drain([&](int32_t f, const Moments& m) { add_face_barycentric_gradient(faces[size_t(f)], m.g, m.q, projection, screen); });
}

template <int kChannels>
void fused_orthographic_backward(const RasterBuffer& raster, std::span<const int32_t> pixels,
                                 const std::vector<Vec3i>& faces, const float* attributes,
                                 const ScreenProjection& projection, const Image& grad_out, float* grad_attributes,
                                 ScreenGradient& screen) {
  struct Moments {
    float g[kChannels] = {};  // sum of the output gradient per channel
    Vec2f q[kChannels];       // sum of gradient x pixel centre per channel
    bool used = false;
    Moments() {
      for (Vec2f& v : q) v.setZero();
    }
  };
  thread_local FaceMoments<Moments> sums;
  if (sums.moments.size() < faces.size()) sums.moments.resize(faces.size());
  const float* grad = grad_out.data.data();
  const int stride = grad_out.channels;
  for (int32_t p : pixels) {
    const float* g = grad + size_t(p) * stride;
    Moments& m = sums.at(raster.face_id[p]);
    const float qx = float(p % raster.width) + 0.5f, qy = float(p / raster.width) + 0.5f;
    for (int c = 0; c < kChannels; ++c) {
      m.g[c] += g[c];
      m.q[c].x() += g[c] * qx;
      m.q[c].y() += g[c] * qy;
    }
  }
  sums.drain([&](int32_t f, const Moments& m) {
    const Vec3i& c = faces[size_t(f)];
    const Vec2f a[3] = {projection.pixel[c[0]], projection.pixel[c[1]], projection.pixel[c[2]]};
    const float area = cross2(a[1] - a[0], a[2] - a[0]);
    if (std::abs(area) < 1e-12f) return;
    // Attributes: dL/d attr_j = sum_p b_j(q_p) g_p with b_j = E_j(q) / A, E_j = cross(a_k - q, a_l - q).
    for (int j = 0; j < 3; ++j) {
      const int k = (j + 1) % 3, l = (j + 2) % 3;
      const float constant = cross2(a[k], a[l]) / area;
      float* out = grad_attributes + size_t(c[j]) * stride;
      for (int ch = 0; ch < kChannels; ++ch)
        out[ch] += constant * m.g[ch] + (cross2(a[l], m.q[ch]) - cross2(a[k], m.q[ch])) / area;
    }
    // Barycentrics: dL/d b_i at a pixel is sum_c g_c (attr_i - attr_0)_c, so its sums follow from the
    // channel sums.
    const float* a0 = attributes + size_t(c[0]) * stride;
    float G[2] = {0.f, 0.f};
    Vec2f Q[2] = {Vec2f::Zero(), Vec2f::Zero()};
    for (int i = 0; i < 2; ++i) {
      const float* ai = attributes + size_t(c[i + 1]) * stride;
      for (int ch = 0; ch < kChannels; ++ch) {
        const float d = ai[ch] - a0[ch];
        G[i] += d * m.g[ch];
        Q[i] += d * m.q[ch];
      }
    }
    add_face_barycentric_gradient(c, G, Q, projection, screen);
  });
}

}  // namespace

void barycentric_backward(const RasterBuffer& raster, std::span<const int32_t> pixels, const std::vector<Vec3i>& faces,
                          const ScreenProjection& projection, const std::vector<Vec2f>& grad_bary,
                          ScreenGradient& screen) {
  if (projection.orthographic) {
    orthographic_backward(raster, pixels, faces, projection, grad_bary, screen);
    return;
  }
  for (int32_t p : pixels) {
    const Vec2f& g = grad_bary[p];
    if (g.x() == 0.f && g.y() == 0.f) continue;
    const Vec3i& f = faces[raster.face_id[p]];
    const Vec2f q(float(p % raster.width) + 0.5f, float(p / raster.width) + 0.5f);
    const Vec2f r[3] = {projection.pixel[f[0]] - q, projection.pixel[f[1]] - q, projection.pixel[f[2]] - q};
    const float w[3] = {projection.w[f[0]], projection.w[f[1]], projection.w[f[2]]};
    // Screen-space barycentrics s_i = E_i / A from the edge functions.
    const float e[3] = {cross2(r[1], r[2]), cross2(r[2], r[0]), cross2(r[0], r[1])};
    const float area = e[0] + e[1] + e[2];
    if (std::abs(area) < 1e-12f) continue;
    float s[3], t[3];
    for (int i = 0; i < 3; ++i) s[i] = e[i] / area;
    // Perspective correction b_i = (s_i / w_i) / sum_j (s_j / w_j).
    float tsum = 0.f;
    for (int i = 0; i < 3; ++i) tsum += (t[i] = s[i] / w[i]);
    const float b[3] = {t[0] / tsum, t[1] / tsum, t[2] / tsum};
    const float gb[3] = {0.f, g.x(), g.y()};  // b0 is dependent: only b1, b2 are outputs
    const float gdotb = gb[1] * b[1] + gb[2] * b[2];
    float gs[3];
    for (int i = 0; i < 3; ++i) {
      const float gt = (gb[i] - gdotb) / tsum;
      gs[i] = gt / w[i];
      screen.w[f[i]] += -gt * t[i] / w[i];
    }
    // s_i = E_i / A with A = sum E_i.
    float garea = 0.f;
    for (int i = 0; i < 3; ++i) garea -= gs[i] * s[i] / area;
    float ge[3];
    for (int i = 0; i < 3; ++i) ge[i] = gs[i] / area + garea;
    // E0 = cross(r1, r2), E1 = cross(r2, r0), E2 = cross(r0, r1).
    screen.pixel[f[1]] += ge[0] * dcross_du(r[2]) + ge[2] * dcross_dv(r[0]);
    screen.pixel[f[2]] += ge[0] * dcross_dv(r[1]) + ge[1] * dcross_du(r[0]);
    screen.pixel[f[0]] += ge[1] * dcross_dv(r[2]) + ge[2] * dcross_du(r[1]);
  }
}


void interpolate_barycentric_backward_orthographic(const RasterBuffer& raster, std::span<const int32_t> pixels,
                                                   const std::vector<Vec3i>& faces, const float* attributes,
                                                   int channels, const ScreenProjection& projection,
                                                   const Image& grad_out, float* grad_attributes,
                                                   ScreenGradient& screen) {
  require(projection.orthographic, "interpolate_barycentric_backward_orthographic: the camera is not orthographic");
  require(channels <= grad_out.channels, "interpolate_barycentric_backward_orthographic: more channels than the gradient has");
  switch (channels) {
    case 1: return fused_orthographic_backward<1>(raster, pixels, faces, attributes, projection, grad_out, grad_attributes, screen);
    case 2: return fused_orthographic_backward<2>(raster, pixels, faces, attributes, projection, grad_out, grad_attributes, screen);
    case 3: return fused_orthographic_backward<3>(raster, pixels, faces, attributes, projection, grad_out, grad_attributes, screen);
    case 4: return fused_orthographic_backward<4>(raster, pixels, faces, attributes, projection, grad_out, grad_attributes, screen);
    default: throw Error("interpolate_barycentric_backward_orthographic: 1 to 4 channels, not " + std::to_string(channels));
  }
}

}  // namespace u3d
