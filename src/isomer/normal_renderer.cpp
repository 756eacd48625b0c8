#include "isomer/normal_renderer.h"

#include <algorithm>
#include <initializer_list>
#include <numeric>

#include "render/barycentric_backward.h"
#include "render/interpolate.h"

namespace u3d {

namespace {

constexpr int kChannels = 4;

// Four explicit stores per pixel and image: with the channel count known the compiler writes them
// directly instead of calling memset for every 16 bytes; one pass over the pixel list for all images.
void zero_pixels(std::initializer_list<Image*> images, const std::vector<int32_t>& pixels) {
  for (int32_t p : pixels)
    for (Image* image : images) {
      float* px = image->data.data() + size_t(p) * kChannels;
      px[0] = px[1] = px[2] = px[3] = 0.f;
    }
}

}  // namespace

std::vector<float> normal_color_attributes(const std::vector<Vec3f>& unit_vectors) {
  std::vector<float> a(unit_vectors.size() * kChannels);
  for (size_t v = 0; v < unit_vectors.size(); ++v) {
    for (int c = 0; c < 3; ++c) a[v * kChannels + c] = 0.5f * (unit_vectors[v][c] + 1.f);
    a[v * kChannels + 3] = 1.f;
  }
  return a;
}

NormalRenderer::NormalRenderer(std::vector<Camera> cameras) {
  views_.resize(cameras.size());
  largest_first_.resize(cameras.size());
  std::iota(largest_first_.begin(), largest_first_.end(), 0);
  for (size_t i = 0; i < cameras.size(); ++i) {
    DifferentiableView& v = views_[i];
    v.camera = cameras[i];
    const int w = v.camera.width, h = v.camera.height;
    v.color = Image(w, h, kChannels);
    v.image = Image(w, h, kChannels);
    v.grad_image = Image(w, h, kChannels);
    v.grad_color = Image(w, h, kChannels);
    if (!v.camera.orthographic) v.grad_bary.assign(size_t(w) * h, Vec2f::Zero());  // only perspective needs it
    v.listed.assign(size_t(w) * h, 0);
  }
}

void NormalRenderer::render(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                            const EdgeTopology& topology, const std::vector<Vec3f>& vertex_normals) {
  attributes_ = normal_color_attributes(vertex_normals);
  neighbors_ = edge_neighbors(faces, topology);
#pragma omp parallel for schedule(dynamic, 1) if (views_.size() > 1)
  for (size_t slot = 0; slot < views_.size(); ++slot) {
    DifferentiableView& v = views_[size_t(largest_first_[slot])];
    // Forget the previous frame's footprint. The losses write grad_image on active pixels alone, so
    // this also leaves it zero everywhere for the new frame.
    zero_pixels({&v.color, &v.image, &v.grad_image}, v.active);
    rasterize_into(positions, faces, v.camera, v.raster, RasterOptions{.cull_backfaces = true});
    v.projection = project_to_screen(positions, v.camera);
    covered_pixels(v.raster, v.covered);
    interpolate(v.raster, v.covered, faces, attributes_.data(), kChannels, v.color);
    for (int32_t p : v.covered)
      std::copy_n(v.color.data.data() + size_t(p) * kChannels, kChannels, v.image.data.data() + size_t(p) * kChannels);
    find_antialias_pairs(v.raster, faces, neighbors_, v.projection, v.pairs);
    apply_antialias(v.pairs, v.color, v.image);
    // Active = covered pixels plus each uncovered pixel a blend changes (once). Only blends move alpha
    // off 1 (covered) or 0 (background), so counting the opaque pixels needs a look at them alone.
    v.active = v.covered;
    v.blended.clear();
    for (const AntialiasPair& pair : v.pairs) {
      const int32_t target = pair.alpha > 0.f ? pair.pixel0 : pair.pixel1;
      if (v.listed[target]) continue;
      v.listed[target] = 1;
      v.blended.push_back(target);
      if (!v.raster.covered(target)) v.active.push_back(target);
    }
    v.opaque_pixels = v.covered.size();
    for (int32_t p : v.blended) {
      v.listed[p] = 0;
      v.opaque_pixels += size_t(v.image.data[size_t(p) * kChannels + 3] > 0.5f);
      v.opaque_pixels -= size_t(v.raster.covered(p));
    }
  }
  std::stable_sort(largest_first_.begin(), largest_first_.end(),
                   [&](int a, int b) { return views_[size_t(a)].active.size() > views_[size_t(b)].active.size(); });
}

void NormalRenderer::render_attribute(const std::vector<Vec3i>& faces, const std::vector<Vec3f>& unit_vectors,
                                      size_t view_index, Image& out) {
  const DifferentiableView& v = views_[view_index];
  const std::vector<float> attributes = normal_color_attributes(unit_vectors);
  // Reuse the scratch and `out` when they already have the view's size (the refinement calls this
  // for every view at every target update).
  for (Image* image : {&attribute_color_, &out}) {
    if (image->width == v.raster.width && image->height == v.raster.height && image->channels == kChannels)
      std::fill(image->data.begin(), image->data.end(), 0.f);
    else
      *image = Image(v.raster.width, v.raster.height, kChannels);
  }
  interpolate(v.raster, v.covered, faces, attributes.data(), kChannels, attribute_color_);
  for (int32_t p : v.covered)
    std::copy_n(attribute_color_.data.data() + size_t(p) * kChannels, kChannels, out.data.data() + size_t(p) * kChannels);
  apply_antialias(v.pairs, attribute_color_, out);
}

void NormalRenderer::backward(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                              const VertexNormals& normals, std::vector<Vec3f>& grad_positions) {
  const size_t n = positions.size();
#pragma omp parallel for schedule(dynamic, 1) if (views_.size() > 1)
  for (size_t slot = 0; slot < views_.size(); ++slot) {
    DifferentiableView& v = views_[size_t(largest_first_[slot])];
    // Identity part of the anti-aliasing backward, then its blend and edge parts.
    for (int32_t p : v.covered)
      std::copy_n(v.grad_image.data.data() + size_t(p) * kChannels, kChannels,
                  v.grad_color.data.data() + size_t(p) * kChannels);
    v.screen_grad.reset(n);
    antialias_backward(v.pairs, v.color, faces, v.projection, v.grad_image, v.grad_color, v.screen_grad);
    v.grad_attributes.assign(n * kChannels, 0.f);
    if (v.projection.orthographic) {  // the four views: one pass, sums per face
      // Alpha is 1 at every vertex: it moves no barycentric, and its attribute gradient is not used.
      interpolate_barycentric_backward_orthographic(v.raster, v.covered, faces, attributes_.data(), 3,
                                                    v.projection, v.grad_color, v.grad_attributes.data(),
                                                    v.screen_grad);
    } else {
      interpolate_backward(v.raster, v.covered, faces, attributes_.data(), kChannels, v.grad_color,
                           v.grad_attributes.data(), &v.grad_bary);
      barycentric_backward(v.raster, v.covered, faces, v.projection, v.grad_bary, v.screen_grad);
    }
    v.grad_positions.assign(n, Vec3f::Zero());
    add_world_gradient(v.projection, positions, v.screen_grad, v.grad_positions);
  }
  // Colour = (n + 1) / 2: the colour gradient reaches the unit normals halved.
  std::vector<Vec3f> grad_normals(n, Vec3f::Zero());
  for (const DifferentiableView& v : views_) {
    for (size_t p = 0; p < n; ++p) {
      grad_positions[p] += v.grad_positions[p];
      for (int c = 0; c < 3; ++c) grad_normals[p][c] += 0.5f * v.grad_attributes[p * kChannels + c];
    }
  }
  vertex_normals_backward(positions, faces, normals, grad_normals, grad_positions);
}

}  // namespace u3d
