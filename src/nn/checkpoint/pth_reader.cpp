#include "nn/checkpoint/pth_reader.h"

#include <c10/core/CPUAllocator.h>
#include <libdeflate.h>

#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>

#include "core/error.h"
#include "nn/checkpoint/mapped_file.h"
#include "nn/checkpoint/pickle_reader.h"
#include "nn/checkpoint/torch_storage.h"
#include "nn/checkpoint/zip_crc.h"

namespace u3d::nn {
namespace {

using pickle::Value;

// A storage record named by a persistent id; read from the archive when a tensor uses it.
struct StorageRef : pickle::Object {
  std::string key;  // record "data/<key>"
  c10::ScalarType dtype;
  int64_t numel;
};

std::string storage_record(const StorageRef& ref) { return "data/" + ref.key; }
size_t storage_bytes(const StorageRef& ref) { return size_t(ref.numel) * c10::elementSize(ref.dtype); }

struct TensorRef : pickle::Object {
  std::shared_ptr<const StorageRef> storage;
  int64_t offset;
  std::vector<int64_t> sizes;
  std::vector<int64_t> strides;
};

int64_t as_int(const Value& v, const std::string& what) {
  require(v.is<int64_t>(), what + " is a " + v.type_name() + ", expected an int");
  return v.as<int64_t>();
}

std::vector<int64_t> as_int_tuple(const Value& v, const std::string& what) {
  require(v.is<std::shared_ptr<pickle::Tuple>>(), what + " is a " + v.type_name() + ", expected a tuple");
  std::vector<int64_t> out;
  for (const Value& item : v.as<std::shared_ptr<pickle::Tuple>>()->items) out.push_back(as_int(item, what + " item"));
  return out;
}

// The whitelist: what torch.save writes for a state dict, and nothing that could run code.
class StateDictHooks : public pickle::PickleHooks {
 public:
  explicit StateDictHooks(std::string source) : source_(std::move(source)) {}

  void check_global(const pickle::Global& g) override {
    const bool allowed = (g.module == "collections" && g.name == "OrderedDict") ||
                         (g.module == "torch._utils" && (g.name == "_rebuild_tensor_v2" || g.name == "_rebuild_parameter")) ||
                         (g.module == "torch" && storage_dtype(g.name));
    require(allowed, source_ + ": refuses the pickled global '" + g.qualified() +
                         "': only plain state dicts of tensors are loaded (no code from the file is run)");
  }

  Value call(const pickle::Global& g, const std::vector<Value>& args) override {
    if (g.name == "OrderedDict") {
      require(args.empty(), source_ + ": OrderedDict built from arguments is not supported");
      return std::make_shared<pickle::Dict>();
    }
    if (g.name == "_rebuild_tensor_v2") {
      // (storage, storage_offset, size, stride, requires_grad, backward_hooks[, metadata])
      require(args.size() == 6 || args.size() == 7,
              source_ + ": _rebuild_tensor_v2 with " + std::to_string(args.size()) + " arguments");
      auto storage = std::dynamic_pointer_cast<const StorageRef>(object_of(args[0]));
      require(storage != nullptr, source_ + ": _rebuild_tensor_v2 without a storage");
      auto t = std::make_shared<TensorRef>();
      t->storage = storage;
      t->offset = as_int(args[1], source_ + ": storage offset");
      t->sizes = as_int_tuple(args[2], source_ + ": tensor size");
      t->strides = as_int_tuple(args[3], source_ + ": tensor stride");
      require(t->sizes.size() == t->strides.size(), source_ + ": tensor size and stride differ in length");
      return std::shared_ptr<const pickle::Object>(t);
    }
    if (g.name == "_rebuild_parameter") {
      // (data, requires_grad, backward_hooks): a Parameter is its data for inference.
      require(args.size() == 3 && std::dynamic_pointer_cast<const TensorRef>(object_of(args[0])),
              source_ + ": malformed _rebuild_parameter");
      return args[0];
    }
    throw Error(source_ + ": '" + g.qualified() + "' cannot be called");
  }

  Value persistent_load(const Value& pid) override {
    // ('storage', torch.<T>Storage, key, location, numel)
    const bool is_tuple = pid.is<std::shared_ptr<pickle::Tuple>>();
    require(is_tuple && pid.as<std::shared_ptr<pickle::Tuple>>()->items.size() == 5,
            source_ + ": unsupported persistent id (" + pid.type_name() + ")");
    const std::vector<Value>& t = pid.as<std::shared_ptr<pickle::Tuple>>()->items;
    require(t[0].is<std::string>() && t[0].as<std::string>() == "storage", source_ + ": persistent id is not a storage");
    const std::optional<c10::ScalarType> dtype =
        t[1].is<pickle::Global>() && t[1].as<pickle::Global>().module == "torch"
            ? storage_dtype(t[1].as<pickle::Global>().name)
            : std::nullopt;
    require(dtype.has_value(), source_ + ": storage of unsupported type " + t[1].type_name());
    require(t[2].is<std::string>(), source_ + ": storage key is a " + t[2].type_name());
    auto storage = std::make_shared<StorageRef>();
    storage->key = t[2].as<std::string>();
    storage->dtype = *dtype;
    storage->numel = as_int(t[4], source_ + ": storage size");
    require(storage->numel >= 0, source_ + ": negative storage size");
    require(storage->numel <= std::numeric_limits<int64_t>::max() / 16, source_ + ": storage size " +
                                                                             std::to_string(storage->numel) + " is too large");
    return std::shared_ptr<const pickle::Object>(storage);
  }

  Value build(const Value& obj, const Value& state) override {
    // torch pickles a state dict's `_metadata` (per-module versions) as OrderedDict state: not needed.
    require(obj.is<std::shared_ptr<pickle::Dict>>(), source_ + ": BUILD on a " + obj.type_name());
    return obj;
  }

 private:
  std::shared_ptr<const pickle::Object> object_of(const Value& v) const {
    return v.is<std::shared_ptr<const pickle::Object>>() ? v.as<std::shared_ptr<const pickle::Object>>() : nullptr;
  }
  std::string source_;
};

void check_zip_magic(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  require(bool(in), "cannot open checkpoint " + path.string());
  char magic[4] = {};
  in.read(magic, 4);
  require(in.gcount() == 4, path.string() + ": file too short to be a PyTorch checkpoint");
  if (uint8_t(magic[0]) == 0x80) {  // the old format starts with a bare pickle (PROTO)
    throw Error(path.string() + ": legacy (pre-1.6, non-zip) torch.save format is not supported; re-save it "
                                "with a recent torch or convert it to .safetensors");
  }
  require(std::string_view(magic, 4) == std::string_view("PK\x03\x04", 4),
          path.string() + ": not a PyTorch zip checkpoint (no zip header)");
}

// Reads records in place from the mapped file and checks each against the CRC-32 in the zip directory
// (torch.save stores records uncompressed, so a record is a view of the mapping; a deflated one, as a
// re-zipped file may hold, is inflated into memory of its own).
class RecordReader {
 public:
  explicit RecordReader(const std::filesystem::path& path)
      : source_(path.string()),
        records_(checked_records(path)),
        file_(std::make_shared<MappedFile>(path, "checkpoint")) {}

  bool has(const std::string& name) const { return records_.count(name) > 0; }
  // The record of a tensor's storage, checked to be in the archive and to hold the storage's bytes (from
  // the zip directory, without reading it).
  std::string storage_record_of(const StorageRef& ref, const std::string& tensor_name) const {
    const std::string record = storage_record(ref);
    auto found = records_.find(record);
    require(found != records_.end(), source_ + ": tensor '" + tensor_name + "': missing record " + record);
    require(found->second.size == storage_bytes(ref),
            source_ + ": tensor '" + tensor_name + "': record " + record + " holds " +
                std::to_string(found->second.size) + " bytes, its storage needs " + std::to_string(storage_bytes(ref)));
    return record;
  }

  // `user` says what needs the record, for errors ("tensor 'conv.weight'").
  c10::Storage read(const std::string& name, const std::string& user) const {
    auto found = records_.find(name);
    require(found != records_.end(), source_ + ": record " + name + " is not in the zip directory");
    const ZipRecord& record = found->second;
    // zip_records checked the range against the size the file had then.
    require(record.offset + record.stored_size <= file_->size(), source_ + ": " + user + ": record " + name +
                                                                     " lies outside the file (it changed while read)");
    file_->populate(record.offset, record.stored_size);
    c10::Storage storage = record.deflated ? inflate(record, name, user)
                                           : mapped_storage(file_, record.offset, record.size);
    require(crc32_of(storage.data(), record.size) == record.crc,
            source_ + ": " + user + ": record " + name + " fails its CRC check (the file is corrupt)");
    return storage;
  }

 private:
  // The zip directory, with the version record torch.save writes.
  static std::map<std::string, ZipRecord> checked_records(const std::filesystem::path& path) {
    std::map<std::string, ZipRecord> records = zip_records(path);
    require(records.count("version") || records.count(".data/version"),
            path.string() + ": zip archive without a version record (not a torch.save file)");
    return records;
  }

  c10::Storage inflate(const ZipRecord& record, const std::string& name, const std::string& user) const {
    c10::Storage storage(c10::Storage::use_byte_size_t(), record.size, c10::GetCPUAllocator(), /*resizable=*/false);
    std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)> decompressor(
        libdeflate_alloc_decompressor(), &libdeflate_free_decompressor);
    require(decompressor != nullptr, source_ + ": out of memory inflating record " + name);
    size_t inflated = 0;
    const libdeflate_result result =
        libdeflate_deflate_decompress(decompressor.get(), file_->data() + record.offset, record.stored_size,
                                      storage.data(), record.size, &inflated);
    require(result == LIBDEFLATE_SUCCESS && inflated == record.size,
            source_ + ": " + user + ": record " + name + " does not inflate to its " + std::to_string(record.size) +
                " bytes (the file is corrupt)");
    return storage;
  }

  std::string source_;
  std::map<std::string, ZipRecord> records_;
  std::shared_ptr<MappedFile> file_;
};

// Reads each storage record once, so tensors sharing a storage share it here too.
class StorageCache {
 public:
  StorageCache(const RecordReader& reader, std::string source) : reader_(reader), source_(std::move(source)) {}

  c10::Storage get(const StorageRef& ref, const std::string& tensor_name) {
    const std::string record = storage_record(ref);
    auto it = cache_.find(ref.key);
    if (it != cache_.end()) {
      // torch.save names each storage once; a key reused with another size (or type) is a corrupt pickle.
      require(it->second.nbytes() == storage_bytes(ref),
              source_ + ": tensor '" + tensor_name + "': record " + record + " is used as storages of " +
                  std::to_string(it->second.nbytes()) + " and " + std::to_string(storage_bytes(ref)) + " bytes");
      return it->second;
    }
    c10::Storage storage = reader_.read(reader_.storage_record_of(ref, tensor_name), "tensor '" + tensor_name + "'");
    cache_.emplace(ref.key, storage);
    return storage;
  }

 private:
  const RecordReader& reader_;
  std::string source_;
  std::map<std::string, c10::Storage> cache_;
};

// Checks that the view lies inside its storage.
void check_view(const TensorRef& ref, const std::string& source, const std::string& name) {
  const auto where = source + ": tensor '" + name + "'";
  int64_t last = ref.offset;  // highest element index the view touches
  bool empty = false;
  for (size_t d = 0; d < ref.sizes.size(); ++d) {
    require(ref.sizes[d] >= 0 && ref.strides[d] >= 0, where + ": negative size or stride");
    if (ref.sizes[d] == 0) {
      empty = true;
      continue;
    }
    int64_t reach = 0;
    require(!__builtin_mul_overflow(ref.sizes[d] - 1, ref.strides[d], &reach) &&
                !__builtin_add_overflow(last, reach, &last),
            where + ": size and stride reach beyond any storage");
  }
  require(ref.offset >= 0 && (empty || last < ref.storage->numel),
          where + ": view (offset " + std::to_string(ref.offset) + ") reaches past its storage of " +
              std::to_string(ref.storage->numel) + " elements");
}

using TensorMaker = std::function<torch::Tensor(const TensorRef&, const std::string& name)>;

// Adds the tensors of `dict` under prefix + key; a nested dict (basicsr's {"params_ema": state dict}) adds
// its tensors under "<key>.".
void add_entries(const pickle::Dict& dict, const std::string& prefix, const TensorMaker& make,
                 const std::string& source, TensorMap& tensors) {
  for (const auto& [key, value] : dict.items) {
    require(key.is<std::string>(), source + ": state dict key is a " + key.type_name());
    const std::string name = prefix + key.as<std::string>();
    if (value.is<std::shared_ptr<pickle::Dict>>() && prefix.empty()) {
      add_entries(*value.as<std::shared_ptr<pickle::Dict>>(), name + ".", make, source, tensors);
      continue;
    }
    auto ref = value.is<std::shared_ptr<const pickle::Object>>()
                   ? std::dynamic_pointer_cast<const TensorRef>(value.as<std::shared_ptr<const pickle::Object>>())
                   : nullptr;
    require(ref != nullptr, source + ": entry '" + name + "' is a " + value.type_name() + ", not a tensor");
    check_view(*ref, source, name);
    tensors[name] = make(*ref, name);
  }
}

// The unpickled state dict of a checkpoint whose zip directory `reader` has read.
pickle::Value read_state_dict(const RecordReader& reader, const std::string& source) {
  if (reader.has("byteorder")) {
    const c10::Storage order = reader.read("byteorder", "byte order");
    require(std::string_view(static_cast<const char*>(order.data()), order.nbytes()) == "little",
            source + ": big-endian checkpoints are not supported");
  }
  require(reader.has("data.pkl"), source + ": zip archive without data.pkl (not a torch.save file)");
  const c10::Storage pkl = reader.read("data.pkl", "the pickled state dict");
  StateDictHooks hooks(source);
  pickle::Value root = pickle::unpickle(std::string_view(static_cast<const char*>(pkl.data()), pkl.nbytes()), hooks,
                                        source + ":data.pkl");
  require(root.is<std::shared_ptr<pickle::Dict>>(),
          source + ": holds a " + root.type_name() + ", expected a state dict {name: tensor}");
  return root;
}

}  // namespace

TensorMap load_pth(const std::filesystem::path& path) {
  check_zip_magic(path);
  const std::string source = path.string();
  RecordReader reader(path);
  const pickle::Value root = read_state_dict(reader, source);
  StorageCache storages(reader, source);
  TensorMap tensors;
  add_entries(
      *root.as<std::shared_ptr<pickle::Dict>>(), "",
      [&](const TensorRef& ref, const std::string& name) {
        return torch::empty({0}, torch::TensorOptions().dtype(ref.storage->dtype))
            .set_(storages.get(*ref.storage, name), ref.offset, ref.sizes, ref.strides);
      },
      source, tensors);
  return tensors;
}

TensorMap inspect_pth(const std::filesystem::path& path) {
  check_zip_magic(path);
  const std::string source = path.string();
  RecordReader reader(path);
  const pickle::Value root = read_state_dict(reader, source);
  TensorMap tensors;
  add_entries(
      *root.as<std::shared_ptr<pickle::Dict>>(), "",
      [&](const TensorRef& ref, const std::string& name) {
        reader.storage_record_of(*ref.storage, name);
        return torch::empty(ref.sizes, torch::TensorOptions().dtype(ref.storage->dtype).device(torch::kMeta));
      },
      source, tensors);
  return tensors;
}

}  // namespace u3d::nn
