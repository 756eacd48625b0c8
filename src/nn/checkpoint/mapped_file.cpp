#include "nn/checkpoint/mapped_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/error.h"

namespace u3d::nn {

namespace {

std::uint64_t page_size() {
  static const auto page = static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
  return page;
}

}  // namespace

MappedFile::MappedFile(const std::filesystem::path& path, const char* what) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error(std::string("cannot open ") + what + " " + path.string() + ": " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw Error(std::string("cannot read ") + what + " " + path.string() + ": not a regular file");
  }
  size_ = static_cast<std::size_t>(st.st_size);
  if (size_ > 0) {
    void* p = ::mmap(nullptr, size_, PROT_READ | PROT_WRITE, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      const int err = errno;
      ::close(fd);
      throw Error(std::string("cannot memory-map ") + what + " " + path.string() + ": " + std::strerror(err));
    }
    data_ = static_cast<std::uint8_t*>(p);
    // Loaders read a file front to back, once.
    ::madvise(p, size_, MADV_SEQUENTIAL);
  }
  ::close(fd);
}

void MappedFile::populate(std::uint64_t offset, std::uint64_t bytes) const {
#ifdef MADV_POPULATE_READ
  const std::uint64_t page = page_size(), first = offset / page * page;
  if (bytes > 0) ::madvise(data_ + first, offset + bytes - first, MADV_POPULATE_READ);
#else
  (void)offset;
  (void)bytes;
#endif
}

MappedFile::~MappedFile() {
  if (data_) ::munmap(data_, size_);
}

namespace {

// What a view's DataPtr owns: the mapping, and the range it views.
struct MappedView {
  std::shared_ptr<MappedFile> file;
  std::uint8_t* begin;
  std::size_t bytes;
};

void free_view(void* context) {
  auto* view = static_cast<MappedView*>(context);
  // Only whole pages inside the view: a page shared with a neighbouring view may still be in use (and,
  // written to, be the process's own copy, which MADV_DONTNEED would drop).
  const std::uintptr_t page = page_size();
  const auto begin = reinterpret_cast<std::uintptr_t>(view->begin);
  const std::uintptr_t first = (begin + page - 1) / page * page, last = (begin + view->bytes) / page * page;
  if (last > first) ::madvise(reinterpret_cast<void*>(first), last - first, MADV_DONTNEED);
  delete view;
}

}  // namespace

c10::Storage mapped_storage(const std::shared_ptr<MappedFile>& file, std::uint64_t offset, std::uint64_t bytes) {
  std::uint8_t* begin = file->data() + offset;
  auto* view = new MappedView{file, begin, static_cast<std::size_t>(bytes)};
  c10::DataPtr data(begin, view, &free_view, c10::Device(c10::DeviceType::CPU));
  return c10::Storage(c10::Storage::use_byte_size_t(), static_cast<std::size_t>(bytes), std::move(data), nullptr,
                      /*resizable=*/false);
}

}  // namespace u3d::nn
