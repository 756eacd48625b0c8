// libFuzzer target: the state dict inside a torch.save checkpoint (nn/checkpoint/pth_reader), i.e. the
// pickle with the reader's real hooks (the allowed globals, persistent storage ids, tensor views checked
// against their storages, storages shared between tensors, nested state dicts). The input is the pickle;
// the harness writes it as data.pkl into a well-formed archive with libtorch's writer, next to storage
// records "data/0" to "data/3" of 16, 32, 64 and 0 bytes (a float storage of 4, 8 or 16 elements, a half
// storage of 8, 16 or 32, ...), then loads the archive both ways. fuzz_pth fuzzes the archive itself.
#include <caffe2/serialize/inline_container.h>

#include <fstream>
#include <string>

#include "fuzz_common.h"
#include "nn/checkpoint/pth_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::filesystem::path path = u3d::fuzz::scratch_dir() / "state_dict.pth";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    caffe2::serialize::PyTorchStreamWriter writer([&](const void* bytes, size_t n) -> size_t {
      out.write(static_cast<const char*>(bytes), std::streamsize(n));
      return out ? n : 0;
    });
    writer.writeRecord("data.pkl", data, size);
    const std::string storage(64, '\x3c');
    const size_t bytes[] = {16, 32, 64, 0};
    for (int i = 0; i < 4; ++i) writer.writeRecord("data/" + std::to_string(i), storage.data(), bytes[i]);
    writer.writeEndOfFile();
    out.close();
    if (!out) std::abort();  // the harness itself failed, not the reader
  }
  u3d::fuzz::expect_clean([&] { u3d::nn::inspect_pth(path); });
  u3d::fuzz::expect_clean([&] { u3d::nn::load_pth(path); });
  return 0;
}
