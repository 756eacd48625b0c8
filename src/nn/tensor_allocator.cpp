#include "nn/tensor_allocator.h"

#include <c10/core/Allocator.h>
#include <c10/core/CPUAllocator.h>
#include <c10/util/Exception.h>
#include <sys/mman.h>

#include <deque>
#include <mutex>
#include <unordered_map>
#include <vector>

namespace u3d::nn {

namespace {

constexpr size_t kGranule = size_t{64} << 10;  // mapped sizes are multiples of this

struct Block {
  void* data;
  size_t bytes;
};

// Every block it hands out has its data pointer as its context and one deleter (`release`), as
// libtorch's raw_allocate / raw_deallocate need (oneDNN's scratch buffers come that way); the deleter
// tells the large blocks by their entry in `large_`.
class TensorAllocator final : public c10::Allocator {
 public:
  c10::DataPtr allocate(size_t n) const override {
    if (n < kLargeBlockBytes) {
      void* data = c10::GetDefaultCPUAllocator()->raw_allocate(n);
      return {data, data, &TensorAllocator::release, c10::Device(c10::DeviceType::CPU)};
    }
    const size_t bytes = (n + kGranule - 1) / kGranule * kGranule;
    void* data = take_cached(bytes);
    if (!data) {
      data = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      TORCH_CHECK(data != MAP_FAILED, "tensor allocator: not enough memory: you tried to allocate ", n, " bytes");
      madvise(data, bytes, MADV_HUGEPAGE);
      std::lock_guard<std::mutex> lock(mutex_);
      large_[data] = bytes;
      mapped_bytes_ += bytes;
      ++stats_.mapped_blocks;
      stats_.new_bytes += bytes;
    }
    report(data, static_cast<int64_t>(bytes));
    return {data, data, &TensorAllocator::release, c10::Device(c10::DeviceType::CPU)};
  }

  c10::DeleterFnPtr raw_deleter() const override { return &TensorAllocator::release; }

  TensorAllocatorStats stats() const {
    std::lock_guard<std::mutex> lock(mutex_);
    TensorAllocatorStats s = stats_;
    s.mapped_bytes = mapped_bytes_;
    s.cached_bytes = cached_bytes_;
    return s;
  }

 private:
  static void release(void* data);

  static void report(void* data, int64_t bytes) {
    if (c10::memoryProfilingEnabled())
      c10::reportMemoryUsageToProfiler(data, bytes, 0, 0, c10::Device(c10::DeviceType::CPU));
  }

  // A block of `bytes` made of cached pages, or nullptr when the cache is empty. The smallest cached
  // block of at least `bytes` is taken, and what it has beyond `bytes` stays in the cache as a block of
  // its own; without one that large, the largest cached block is grown to `bytes` (mremap keeps its
  // pages, only the added ones are new).
  void* take_cached(size_t bytes) const {
    Block taken{nullptr, 0};
    {
      std::lock_guard<std::mutex> lock(mutex_);
      auto smallest_fit = cache_.end(), largest = cache_.end();
      for (auto it = cache_.begin(); it != cache_.end(); ++it) {
        if (it->bytes >= bytes && (smallest_fit == cache_.end() || it->bytes < smallest_fit->bytes)) smallest_fit = it;
        if (largest == cache_.end() || it->bytes > largest->bytes) largest = it;
      }
      const auto best = smallest_fit != cache_.end() ? smallest_fit : largest;
      if (best == cache_.end()) return nullptr;
      taken = *best;
      cache_.erase(best);
      cached_bytes_ -= taken.bytes;
      ++stats_.reused_blocks;
      if (taken.bytes > bytes) {
        const Block rest{static_cast<char*>(taken.data) + bytes, taken.bytes - bytes};
        cache_.push_back(rest);
        cached_bytes_ += rest.bytes;
        large_[rest.data] = rest.bytes;
        large_[taken.data] = bytes;
      }
    }
    if (taken.bytes >= bytes) return taken.data;
    void* grown = mremap(taken.data, taken.bytes, bytes, MREMAP_MAYMOVE);
    std::lock_guard<std::mutex> lock(mutex_);
    large_.erase(taken.data);
    if (grown == MAP_FAILED) {  // the old mapping is still there: give it up and map anew
      --stats_.reused_blocks;
      mapped_bytes_ -= taken.bytes;
      munmap(taken.data, taken.bytes);
      return nullptr;
    }
    large_[grown] = bytes;
    mapped_bytes_ += bytes - taken.bytes;
    stats_.new_bytes += bytes - taken.bytes;
    return grown;
  }

  // Frees a large block: it goes to the cache, and the oldest cached ones are unmapped while the cache
  // is over its bound (a block larger than the whole cache is unmapped at once). Returns its size, or 0
  // (doing nothing) for a pointer that is not a large block.
  size_t give_back(void* data) const {
    std::vector<Block> unmapped;
    size_t bytes = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto found = large_.find(data);
      if (found == large_.end()) return 0;
      bytes = found->second;
      const Block block{data, bytes};
      if (block.bytes > kLargeBlockCacheBytes) {
        unmapped.push_back(block);
      } else {
        cache_.push_back(block);
        cached_bytes_ += block.bytes;
        while (cached_bytes_ > kLargeBlockCacheBytes) {
          unmapped.push_back(cache_.front());
          cached_bytes_ -= cache_.front().bytes;
          cache_.pop_front();
        }
      }
      for (const Block& b : unmapped) {
        large_.erase(b.data);
        mapped_bytes_ -= b.bytes;
      }
    }
    for (const Block& b : unmapped) munmap(b.data, b.bytes);
    return bytes;
  }

  mutable std::mutex mutex_;
  mutable std::unordered_map<void*, size_t> large_;  // every mapped block, in use or cached: its size
  mutable std::deque<Block> cache_;                  // freed large blocks, oldest first
  mutable size_t cached_bytes_ = 0, mapped_bytes_ = 0;
  mutable TensorAllocatorStats stats_;
};

// Never destroyed: tensors may outlive every other static.
TensorAllocator& instance() {
  static auto* allocator = new TensorAllocator();
  return *allocator;
}

void TensorAllocator::release(void* data) {
  if (!data) return;
  if (const size_t bytes = instance().give_back(data))
    report(data, -static_cast<int64_t>(bytes));
  else
    c10::GetDefaultCPUAllocator()->raw_deallocate(data);
}

}  // namespace

void install_tensor_allocator() {
  static std::once_flag once;
  // Above the default allocator's registration (priority 0).
  std::call_once(once, [] { c10::SetCPUAllocator(&instance(), /*priority=*/1); });
}

TensorAllocatorStats tensor_allocator_stats() { return instance().stats(); }

}  // namespace u3d::nn
