#include "nn/checkpoint/safetensors.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "nn/checkpoint/mapped_file.h"

namespace u3d::nn {

namespace fs = std::filesystem;

static_assert(std::endian::native == std::endian::little,
              "safetensors data is little-endian; a big-endian host would need byte swapping");

namespace {

// The header is JSON text; anything this large is a corrupt length field, not a real header.
constexpr std::uint64_t kMaxHeaderBytes = 100ull << 20;

struct DtypeInfo {
  const char* name;
  torch::ScalarType type;
  std::size_t bytes;
};

constexpr DtypeInfo kDtypes[] = {
    {"F32", torch::kFloat32, 4}, {"F16", torch::kFloat16, 2}, {"BF16", torch::kBFloat16, 2},
    {"F64", torch::kFloat64, 8}, {"I64", torch::kInt64, 8},   {"I32", torch::kInt32, 4},
    {"U8", torch::kUInt8, 1},    {"BOOL", torch::kBool, 1},
};

const DtypeInfo* dtype_by_name(const std::string& name) {
  for (const auto& d : kDtypes)
    if (name == d.name) return &d;
  return nullptr;
}

const DtypeInfo* dtype_by_type(torch::ScalarType type) {
  for (const auto& d : kDtypes)
    if (type == d.type) return &d;
  return nullptr;
}

struct Entry {
  std::string name;
  const DtypeInfo* dtype;
  std::vector<int64_t> shape;
  std::uint64_t begin, end;  // relative to the start of the data section
};

std::uint64_t json_uint(const nlohmann::json& v, const std::string& what, const std::string& context) {
  if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<int64_t>() >= 0))
    throw Error(context + ": " + what + " must be a non-negative integer, got " + v.dump());
  return v.get<std::uint64_t>();
}

Entry parse_entry(const std::string& name, const nlohmann::json& j, const std::string& file) {
  const std::string ctx = "safetensors file " + file + ", tensor '" + name + "'";
  if (!j.is_object()) throw Error(ctx + ": header entry is not an object");
  for (const char* key : {"dtype", "shape", "data_offsets"})
    if (!j.contains(key)) throw Error(ctx + ": header entry lacks '" + key + "'");

  Entry e;
  e.name = name;
  if (!j["dtype"].is_string()) throw Error(ctx + ": dtype is not a string");
  e.dtype = dtype_by_name(j["dtype"].get<std::string>());
  if (!e.dtype) throw Error(ctx + ": unsupported dtype " + j["dtype"].dump());

  const auto& shape = j["shape"];
  if (!shape.is_array()) throw Error(ctx + ": shape is not an array");
  // numel in 128 bits would be overkill; reject products that overflow 64 bits instead.
  std::uint64_t numel = 1;
  bool overflow = false;
  for (const auto& d : shape) {
    std::uint64_t dim = json_uint(d, "shape dimension", ctx);
    if (dim > static_cast<std::uint64_t>(std::numeric_limits<int64_t>::max())) overflow = true;
    e.shape.push_back(static_cast<int64_t>(dim));
    if (dim != 0 && numel > std::numeric_limits<std::uint64_t>::max() / dim) overflow = true;
    numel *= dim;
  }
  const auto& off = j["data_offsets"];
  if (!off.is_array() || off.size() != 2) throw Error(ctx + ": data_offsets must be [begin, end]");
  e.begin = json_uint(off[0], "data_offsets[0]", ctx);
  e.end = json_uint(off[1], "data_offsets[1]", ctx);
  if (e.end < e.begin) throw Error(ctx + ": data_offsets end " + std::to_string(e.end) + " < begin " + std::to_string(e.begin));
  if (overflow || numel > std::numeric_limits<std::uint64_t>::max() / e.dtype->bytes)
    throw Error(ctx + ": shape " + shape.dump() + " is too large");
  std::uint64_t expected = numel * e.dtype->bytes;
  if (expected != e.end - e.begin)
    throw Error(ctx + ": shape " + shape.dump() + " of " + e.dtype->name + " needs " + std::to_string(expected) +
                " bytes but data_offsets span " + std::to_string(e.end - e.begin));
  return e;
}

// The header's entries, checked against the file size, sorted by offset. `head` holds the file's first
// head_size bytes, which include the header whenever the file does.
std::vector<Entry> read_header(const std::uint8_t* head, std::uint64_t head_size, std::uint64_t file_size,
                               const std::string& file, std::uint64_t& data_begin) {
  if (file_size < 8)
    throw Error("safetensors file " + file + " is truncated: " + std::to_string(file_size) + " bytes, no header length");
  std::uint64_t header_len = 0;
  std::memcpy(&header_len, head, 8);
  if (header_len > kMaxHeaderBytes || header_len > file_size - 8 || header_len > head_size - 8)
    throw Error("safetensors file " + file + ": header length " + std::to_string(header_len) + " exceeds the file size " +
                std::to_string(file_size) + " (truncated or not a safetensors file)");

  nlohmann::json header;
  try {
    header = nlohmann::json::parse(head + 8, head + 8 + header_len);
  } catch (const nlohmann::json::exception& e) {
    throw Error("safetensors file " + file + ": header is not valid JSON (" + e.what() + ")");
  }
  if (!header.is_object()) throw Error("safetensors file " + file + ": header is not a JSON object");

  data_begin = 8 + header_len;
  const std::uint64_t data_size = file_size - data_begin;
  std::vector<Entry> entries;
  for (const auto& [name, value] : header.items()) {
    if (name == "__metadata__") continue;  // free-form string map, not a tensor
    Entry e = parse_entry(name, value, file);
    if (e.end > data_size)
      throw Error("safetensors file " + file + ", tensor '" + name + "': data_offsets [" + std::to_string(e.begin) + ", " +
                  std::to_string(e.end) + "] lie beyond the data section of " + std::to_string(data_size) +
                  " bytes (truncated file?)");
    entries.push_back(std::move(e));
  }

  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.begin != b.begin ? a.begin < b.begin : a.end < b.end; });
  // Compare each tensor with the one reaching furthest so far, so a long range covering several later
  // ones is caught too. Empty tensors occupy no bytes and cannot overlap.
  const Entry* furthest = nullptr;
  for (const Entry& cur : entries) {
    if (cur.begin == cur.end) continue;
    if (furthest && cur.begin < furthest->end)
      throw Error("safetensors file " + file + ": tensors '" + furthest->name + "' and '" + cur.name +
                  "' overlap in the data section");
    if (!furthest || cur.end > furthest->end) furthest = &cur;
  }
  return entries;
}

}  // namespace

TensorMap load_safetensors(const fs::path& path) {
  const std::string file = path.string();
  const auto map = std::make_shared<MappedFile>(path, "safetensors file");
  std::uint64_t data_begin = 0;
  const std::vector<Entry> entries = read_header(map->data(), map->size(), map->size(), file, data_begin);

  map->populate(data_begin, map->size() - data_begin);  // the loader reads every tensor next
  TensorMap out;
  for (const Entry& e : entries) {
    const c10::Storage storage = mapped_storage(map, data_begin + e.begin, e.end - e.begin);
    out.emplace(e.name, torch::empty({0}, torch::TensorOptions().dtype(e.dtype->type)).set_(storage, 0, e.shape));
  }
  return out;
}

TensorMap inspect_safetensors(const fs::path& path) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  if (!in || !fs::is_regular_file(path, ec)) throw Error("cannot open safetensors file " + file);
  const std::uint64_t file_size = fs::file_size(path);
  std::vector<std::uint8_t> head(std::min<std::uint64_t>(file_size, 8));
  in.read(reinterpret_cast<char*>(head.data()), std::streamsize(head.size()));
  if (file_size >= 8) {
    std::uint64_t header_len = 0;
    std::memcpy(&header_len, head.data(), 8);
    if (header_len <= kMaxHeaderBytes && header_len <= file_size - 8) {
      head.resize(8 + header_len);
      in.read(reinterpret_cast<char*>(head.data() + 8), std::streamsize(header_len));
    }
  }
  std::uint64_t data_begin = 0;
  TensorMap out;
  for (const Entry& e : read_header(head.data(), head.size(), file_size, file, data_begin))
    out.emplace(e.name, torch::empty(e.shape, torch::TensorOptions().dtype(e.dtype->type).device(torch::kMeta)));
  return out;
}

void save_safetensors(const TensorMap& tensors, const fs::path& path) {
  nlohmann::json header = nlohmann::json::object();
  std::vector<torch::Tensor> payload;
  std::uint64_t offset = 0;
  for (const auto& [name, tensor] : tensors) {
    if (name == "__metadata__") throw Error("cannot write " + path.string() + ": '__metadata__' is reserved, not a tensor name");
    if (!tensor.defined()) throw Error("cannot write " + path.string() + ": tensor '" + name + "' is undefined");
    const DtypeInfo* dtype = dtype_by_type(tensor.scalar_type());
    if (!dtype)
      throw Error("cannot write " + path.string() + ": tensor '" + name + "' has dtype " +
                  std::string(c10::toString(tensor.scalar_type())) + ", which safetensors files here do not support");
    torch::Tensor t = tensor.detach().to(torch::kCPU).contiguous();
    std::uint64_t bytes = static_cast<std::uint64_t>(t.numel()) * dtype->bytes;
    header[name] = {{"dtype", dtype->name}, {"shape", t.sizes().vec()}, {"data_offsets", {offset, offset + bytes}}};
    offset += bytes;
    payload.push_back(std::move(t));
  }
  std::string text = header.dump();
  // Pad with spaces so the data section starts 8-byte aligned, as the reference writer does.
  text.append((8 - text.size() % 8) % 8, ' ');
  const std::uint64_t header_len = text.size();

  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream os(tmp, std::ios::binary | std::ios::trunc);
    if (!os) throw Error("cannot write " + path.string() + ": cannot create " + tmp.string());
    os.write(reinterpret_cast<const char*>(&header_len), 8);
    os.write(text.data(), static_cast<std::streamsize>(text.size()));
    for (const auto& t : payload)
      os.write(static_cast<const char*>(t.data_ptr()), static_cast<std::streamsize>(t.numel() * t.element_size()));
    os.flush();
    if (!os) throw Error("cannot write " + path.string() + ": write failed (disk full?)");
  });
}

}  // namespace u3d::nn
