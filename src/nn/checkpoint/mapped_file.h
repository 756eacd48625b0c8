#pragma once
// A weights file mapped into memory, and tensors that view it: the checkpoint readers (safetensors.h,
// pth_reader.h) hand out views of the mapping instead of copies, so a file's bytes are neither read into
// fresh memory nor copied before the loader converts them into a model (state_dict_loader.h). The
// mapping is private and writable: writing to a view copies that page for the process and never
// touches the file. It stays mapped while any view lives; when a view is freed, the pages that lie
// wholly inside it leave the process (they stay in the page cache), so loading a model does not hold
// the whole file resident beside it.
#include <torch/torch.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>

namespace u3d::nn {

class MappedFile {
 public:
  // Maps the whole file; `what` names it in errors ("safetensors file", "checkpoint").
  MappedFile(const std::filesystem::path& path, const char* what);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  std::uint8_t* data() const { return data_; }
  std::size_t size() const { return size_; }
  // Maps the range's pages in one call (reading them from the disk where the page cache lacks them),
  // instead of one page fault per few pages as they are first read. A hint: without it (kernels before
  // 5.14) the pages come by faults.
  void populate(std::uint64_t offset, std::uint64_t bytes) const;

 private:
  std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
};

// The bytes [offset, offset + bytes) of the file as an untyped storage that keeps the mapping alive.
// The caller has checked that the range lies in the file.
c10::Storage mapped_storage(const std::shared_ptr<MappedFile>& file, std::uint64_t offset, std::uint64_t bytes);

}  // namespace u3d::nn
