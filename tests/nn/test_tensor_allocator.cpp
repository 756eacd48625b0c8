#include "nn/tensor_allocator.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

namespace u3d::nn {
namespace {

constexpr int64_t kLargeFloats = int64_t(kLargeBlockBytes / sizeof(float));

TEST(TensorAllocator, FreedLargeBlockServesTheNextRequestOfItsSize) {
  install_tensor_allocator();
  const void* first = nullptr;
  {
    torch::Tensor a = torch::full({kLargeFloats + 5}, 3.0f);
    first = a.data_ptr();
    EXPECT_EQ(a.sum().item<double>(), 3.0 * double(kLargeFloats + 5));
  }
  const TensorAllocatorStats before = tensor_allocator_stats();
  torch::Tensor b = torch::empty({kLargeFloats + 5});
  EXPECT_EQ(b.data_ptr(), first);
  EXPECT_EQ(tensor_allocator_stats().reused_blocks, before.reused_blocks + 1);
  b.fill_(2.0f);
  EXPECT_EQ(b.sum().item<double>(), 2.0 * double(kLargeFloats + 5));
}

TEST(TensorAllocator, CachedPagesServeRequestsOfOtherSizes) {
  install_tensor_allocator();
  constexpr int64_t kCacheFloats = int64_t(kLargeBlockCacheBytes / sizeof(float));
  // A freed block as large as the whole cache is left alone in it.
  const void* start = nullptr;
  {
    torch::Tensor whole = torch::full({kCacheFloats}, 1.0f);
    start = whole.data_ptr();
  }
  EXPECT_EQ(tensor_allocator_stats().cached_bytes, kLargeBlockCacheBytes);
  const TensorAllocatorStats before = tensor_allocator_stats();
  // A smaller request takes its first part; the rest stays cached.
  torch::Tensor part = torch::empty({kLargeFloats * 3});
  EXPECT_EQ(part.data_ptr(), start);
  EXPECT_EQ(tensor_allocator_stats().cached_bytes, kLargeBlockCacheBytes - 3 * kLargeBlockBytes);
  // A request larger than every cached block grows the largest: only the added pages are new.
  torch::Tensor grown = torch::empty({kCacheFloats - kLargeFloats * 3 + kLargeFloats});
  const TensorAllocatorStats after = tensor_allocator_stats();
  EXPECT_EQ(after.cached_bytes, 0u);
  EXPECT_EQ(after.mapped_blocks, before.mapped_blocks);
  EXPECT_EQ(after.reused_blocks, before.reused_blocks + 2);
  EXPECT_EQ(after.new_bytes, before.new_bytes + kLargeBlockBytes);
  part.fill_(2.0f);
  grown.fill_(3.0f);
  EXPECT_EQ(part.min().item<float>(), 2.0f);
  EXPECT_EQ(part.max().item<float>(), 2.0f);
  EXPECT_EQ(grown.min().item<float>(), 3.0f);
  EXPECT_EQ(grown.max().item<float>(), 3.0f);
}

TEST(TensorAllocator, CacheStaysWithinItsBound) {
  install_tensor_allocator();
  // Freed blocks of many sizes, together four times the cache's bound.
  size_t freed = 0;
  for (int64_t i = 0; freed < 4 * kLargeBlockCacheBytes; ++i) {
    torch::Tensor t = torch::ones({kLargeFloats + i * (int64_t(1) << 20)});
    freed += size_t(t.nbytes());
  }
  const TensorAllocatorStats s = tensor_allocator_stats();
  EXPECT_LE(s.cached_bytes, kLargeBlockCacheBytes);
  EXPECT_GT(s.cached_bytes, 0u);
  // A block larger than the whole cache is unmapped when freed (with the cached pages it was grown from).
  const size_t mapped = s.mapped_bytes;
  { torch::Tensor huge = torch::zeros({int64_t(kLargeBlockCacheBytes / sizeof(float)) + 1}); }
  EXPECT_LE(tensor_allocator_stats().mapped_bytes, mapped);
}

TEST(TensorAllocator, SmallTensorsStayWithLibtorchsAllocator) {
  install_tensor_allocator();
  const TensorAllocatorStats before = tensor_allocator_stats();
  torch::Tensor small = torch::arange(1000, torch::kFloat);
  EXPECT_EQ(small.sum().item<double>(), 999.0 * 1000.0 / 2.0);
  const TensorAllocatorStats after = tensor_allocator_stats();
  EXPECT_EQ(after.mapped_blocks + after.reused_blocks, before.mapped_blocks + before.reused_blocks);
}

}  // namespace
}  // namespace u3d::nn
