#include "nn/checkpoint/pth_writer.h"

#include <caffe2/serialize/inline_container.h>

#include <fstream>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "nn/checkpoint/pickle_writer.h"
#include "nn/checkpoint/torch_storage.h"

namespace u3d::nn {

void save_pth(const TensorMap& tensors, const std::filesystem::path& path) {
  pickle::PickleWriter pkl;
  std::vector<torch::Tensor> storages;
  pkl.empty_ordered_dict().mark();
  for (const auto& [name, tensor] : tensors) {
    const std::string_view storage = storage_name(tensor.scalar_type());
    require(!storage.empty(), "cannot save tensor '" + name + "' of " + std::string(c10::toString(tensor.scalar_type())) +
                                  " to " + path.string() + ": no torch storage type for it");
    const torch::Tensor data = tensor.detach().to(torch::kCPU).contiguous();
    pkl.str(name).tensor(std::string(storage), std::to_string(storages.size()), data.numel(), 0, data.sizes().vec(),
                         data.strides().vec());
    storages.push_back(data);
  }
  pkl.op('u');  // SETITEMS
  const std::string bytes = pkl.finish();

  write_atomically(path, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    require(bool(out), "cannot write " + temporary.string());
    try {
      caffe2::serialize::PyTorchStreamWriter writer([&](const void* data, size_t size) -> size_t {
        out.write(static_cast<const char*>(data), std::streamsize(size));
        return out ? size : 0;
      });
      writer.writeRecord("data.pkl", bytes.data(), bytes.size());
      writer.writeRecord("byteorder", "little", 6);
      for (size_t i = 0; i < storages.size(); ++i)
        writer.writeRecord("data/" + std::to_string(i), storages[i].data_ptr(), storages[i].nbytes());
      writer.writeEndOfFile();
    } catch (const c10::Error& e) {
      const std::string what = e.what_without_backtrace();
      throw Error("cannot write " + path.string() + ": " + what.substr(0, what.find('\n')));
    }
    out.close();
    require(bool(out), "cannot write " + temporary.string() + " (disk full?)");
  });
}

}  // namespace u3d::nn
