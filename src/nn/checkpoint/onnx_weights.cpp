#include "nn/checkpoint/onnx_weights.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <optional>
#include <string_view>

#include "core/error.h"

namespace u3d::nn {
namespace {

// Field numbers of onnx.proto3 that the reader needs.
constexpr uint32_t kModelGraph = 7;
constexpr uint32_t kGraphNode = 1, kGraphInitializer = 5;
constexpr uint32_t kNodeInput = 1, kNodeOutput = 2, kNodeName = 3, kNodeOpType = 4;
constexpr uint32_t kTensorDims = 1, kTensorDataType = 2, kTensorFloatData = 4, kTensorInt32Data = 5,
                   kTensorInt64Data = 7, kTensorName = 8, kTensorRawData = 9, kTensorDoubleData = 10,
                   kTensorExternalData = 13, kTensorDataLocation = 14;
// TensorProto.DataType values.
constexpr int kFloat = 1, kInt32 = 6, kInt64 = 7, kFloat16 = 10, kDouble = 11;

enum Wire : uint32_t { kVarint = 0, kFixed64 = 1, kLengthDelimited = 2, kFixed32 = 5 };

struct Field {
  uint32_t number = 0;
  Wire wire = kVarint;
  uint64_t varint = 0;     // kVarint, kFixed64, kFixed32
  std::string_view bytes;  // kLengthDelimited
};

// Reads the fields of one protobuf message. Every read is bounds-checked; errors name `where`.
class Message {
 public:
  Message(std::string_view data, const std::string& where) : data_(data), where_(where) {}

  std::optional<Field> next() {
    if (pos_ == data_.size()) return std::nullopt;
    const uint64_t key = varint();
    Field f;
    f.number = static_cast<uint32_t>(key >> 3);
    require(f.number != 0, where_ + ": corrupt protobuf (field number 0)");
    switch (key & 7) {
      case kVarint:
        f.wire = kVarint;
        f.varint = varint();
        break;
      case kFixed64:
        f.wire = kFixed64;
        f.varint = fixed(8);
        break;
      case kFixed32:
        f.wire = kFixed32;
        f.varint = fixed(4);
        break;
      case kLengthDelimited: {
        f.wire = kLengthDelimited;
        const uint64_t n = varint();
        require(n <= data_.size() - pos_, where_ + ": truncated or corrupt file (a field runs past its end)");
        f.bytes = data_.substr(pos_, n);
        pos_ += n;
        break;
      }
      default: throw Error(where_ + ": corrupt protobuf (wire type " + std::to_string(key & 7) + ")");
    }
    return f;
  }

  uint64_t varint() {
    uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      require(pos_ < data_.size(), where_ + ": truncated or corrupt file (varint runs past the end)");
      const auto b = static_cast<uint8_t>(data_[pos_++]);
      v |= uint64_t(b & 0x7f) << shift;
      if (!(b & 0x80)) return v;
    }
    throw Error(where_ + ": corrupt protobuf (varint longer than 10 bytes)");
  }

  bool done() const { return pos_ == data_.size(); }

 private:
  uint64_t fixed(size_t n) {
    require(n <= data_.size() - pos_, where_ + ": truncated or corrupt file (fixed field runs past the end)");
    uint64_t v = 0;
    std::memcpy(&v, data_.data() + pos_, n);  // little-endian host (checked by the callers' platforms)
    pos_ += n;
    return v;
  }

  std::string_view data_;
  size_t pos_ = 0;
  std::string where_;
};

std::string to_string(std::string_view s) { return std::string(s.data(), s.size()); }

void expect_wire(const Field& f, Wire wire, const std::string& where, const char* what) {
  require(f.wire == wire, where + ": corrupt protobuf (" + what + " has wire type " + std::to_string(f.wire) + ")");
}

// A repeated scalar field, packed (one length-delimited run) or not (one field per value).
template <class T>
void append_repeated(const Field& f, std::vector<T>& out, const std::string& where) {
  if (f.wire != kLengthDelimited) {
    out.push_back(static_cast<T>(f.varint));
    return;
  }
  Message packed(f.bytes, where);
  while (!packed.done()) out.push_back(static_cast<T>(packed.varint()));
}

template <class T>
void append_fixed(const Field& f, std::vector<T>& out, const std::string& where) {
  if (f.wire != kLengthDelimited) {
    require(f.wire == (sizeof(T) == 4 ? kFixed32 : kFixed64), where + ": corrupt protobuf (typed data)");
    T v;
    std::memcpy(&v, &f.varint, sizeof(T));
    out.push_back(v);
    return;
  }
  require(f.bytes.size() % sizeof(T) == 0, where + ": truncated typed data");
  const size_t n = f.bytes.size() / sizeof(T);
  if (n == 0) return;  // (memcpy to an empty vector's null data() is undefined even for 0 bytes)
  const size_t old = out.size();
  out.resize(old + n);
  std::memcpy(out.data() + old, f.bytes.data(), f.bytes.size());
}

std::pair<std::string, torch::Tensor> parse_tensor(std::string_view bytes, const std::string& source) {
  std::string name;
  std::vector<int64_t> dims;
  int data_type = 0;
  std::optional<std::string_view> raw;
  std::vector<float> floats;
  std::vector<double> doubles;
  std::vector<int64_t> int64s;
  std::vector<int32_t> int32s;
  bool external = false;
  // The name may come after the data: parse everything, then decode.
  Message m(bytes, source + ": initializer");
  while (auto f = m.next()) {
    const std::string where = source + ": initializer '" + name + "'";
    switch (f->number) {
      case kTensorName:
        expect_wire(*f, kLengthDelimited, where, "name");
        name = to_string(f->bytes);
        break;
      case kTensorDims: append_repeated(*f, dims, where); break;
      case kTensorDataType:
        expect_wire(*f, kVarint, where, "data_type");
        data_type = static_cast<int>(f->varint);
        break;
      case kTensorRawData:
        expect_wire(*f, kLengthDelimited, where, "raw_data");
        raw = f->bytes;
        break;
      case kTensorFloatData: append_fixed(*f, floats, where); break;
      case kTensorDoubleData: append_fixed(*f, doubles, where); break;
      case kTensorInt64Data: append_repeated(*f, int64s, where); break;
      case kTensorInt32Data: append_repeated(*f, int32s, where); break;
      case kTensorExternalData: external = true; break;
      case kTensorDataLocation: external = external || f->varint == 1; break;
      default: break;
    }
  }
  const std::string where = source + ": initializer '" + name + "'";
  require(!external, where + " keeps its data in an external file, which is not supported");
  int64_t count = 1;
  for (int64_t d : dims) {
    require(d >= 0 && (d == 0 || count <= (int64_t{1} << 40) / d), where + ": invalid dims");
    count *= d;
  }
  torch::ScalarType type;
  switch (data_type) {
    case kFloat: type = torch::kFloat; break;
    case kFloat16: type = torch::kHalf; break;
    case kDouble: type = torch::kDouble; break;
    case kInt32: type = torch::kInt; break;
    case kInt64: type = torch::kLong; break;
    default:
      throw Error(where + " has ONNX data type " + std::to_string(data_type) +
                  "; only FLOAT, FLOAT16, DOUBLE, INT32 and INT64 are read");
  }
  torch::Tensor t = torch::empty(dims, torch::TensorOptions().dtype(type));
  const size_t nbytes = static_cast<size_t>(count) * t.element_size();
  auto check_count = [&](size_t n) {
    require(n == static_cast<size_t>(count), where + ": holds " + std::to_string(n) + " values, its dims need " +
                                                 std::to_string(count) + " (truncated or corrupt)");
  };
  if (raw) {
    require(raw->size() == nbytes, where + ": raw_data has " + std::to_string(raw->size()) + " bytes, its dims need " +
                                       std::to_string(nbytes) + " (truncated or corrupt)");
    if (nbytes) std::memcpy(t.data_ptr(), raw->data(), nbytes);
  } else if (type == torch::kFloat) {
    check_count(floats.size());
    if (nbytes) std::memcpy(t.data_ptr(), floats.data(), nbytes);
  } else if (type == torch::kDouble) {
    check_count(doubles.size());
    if (nbytes) std::memcpy(t.data_ptr(), doubles.data(), nbytes);
  } else if (type == torch::kLong) {
    check_count(int64s.size());
    if (nbytes) std::memcpy(t.data_ptr(), int64s.data(), nbytes);
  } else {
    // INT32 as is; FLOAT16 keeps its bit patterns in the low 16 bits of int32_data.
    check_count(int32s.size());
    if (type == torch::kInt) {
      if (nbytes) std::memcpy(t.data_ptr(), int32s.data(), nbytes);
    } else {
      auto* out = static_cast<uint16_t*>(t.data_ptr());
      for (size_t i = 0; i < int32s.size(); ++i) out[i] = static_cast<uint16_t>(int32s[i]);
    }
  }
  return {name, t};
}

OnnxNode parse_node(std::string_view bytes, const std::string& source) {
  OnnxNode node;
  Message m(bytes, source + ": node");
  while (auto f = m.next()) {
    if (f->number < kNodeInput || f->number > kNodeOpType) continue;
    expect_wire(*f, kLengthDelimited, source + ": node '" + node.name + "'", "a string field");
    std::string s = to_string(f->bytes);
    if (f->number == kNodeInput)
      node.inputs.push_back(std::move(s));
    else if (f->number == kNodeOutput)
      node.outputs.push_back(std::move(s));
    else if (f->number == kNodeName)
      node.name = std::move(s);
    else
      node.op_type = std::move(s);
  }
  return node;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

OnnxGraph load_onnx(const std::filesystem::path& path) {
  const std::string source = path.string();
  std::ifstream in(path, std::ios::binary);
  require(bool(in) && std::filesystem::is_regular_file(path), "cannot open ONNX file " + source);
  std::string data(std::filesystem::file_size(path), '\0');
  in.read(data.data(), static_cast<std::streamsize>(data.size()));
  require(in.gcount() == static_cast<std::streamsize>(data.size()), "cannot read ONNX file " + source);

  OnnxGraph graph;
  bool has_graph = false;
  Message model(data, source);
  while (auto f = model.next()) {
    if (f->number != kModelGraph) continue;
    expect_wire(*f, kLengthDelimited, source, "graph");
    has_graph = true;
    Message g(f->bytes, source + ": graph");
    while (auto gf = g.next()) {
      if (gf->number == kGraphNode) {
        expect_wire(*gf, kLengthDelimited, source, "node");
        graph.nodes.push_back(parse_node(gf->bytes, source));
      } else if (gf->number == kGraphInitializer) {
        expect_wire(*gf, kLengthDelimited, source, "initializer");
        auto [name, tensor] = parse_tensor(gf->bytes, source);
        require(!graph.initializers.count(name), source + ": initializer '" + name + "' appears twice");
        graph.initializers.emplace(std::move(name), std::move(tensor));
      }
    }
  }
  require(has_graph && !graph.nodes.empty(), source + ": not an ONNX model (no graph with nodes)");
  return graph;
}

bool is_onnx_path(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".onnx";
}

TensorMap conv_weights_in_graph_order(const OnnxGraph& graph, const std::vector<std::string>& conv_modules,
                                      const std::string& source) {
  std::vector<const OnnxNode*> convs;
  for (const auto& node : graph.nodes) {
    require(node.op_type != "BatchNormalization",
            source + ": node '" + node.name +
                "' is an unfolded BatchNormalization; only exports with BatchNorm "
                "folded into the convolutions (torch.onnx.export in eval mode) are read");
    if (node.op_type == "Conv") convs.push_back(&node);
  }
  require(convs.size() == conv_modules.size(),
          source + ": has " + std::to_string(convs.size()) + " Conv nodes, the network has " +
              std::to_string(conv_modules.size()) + " convolutions (a file of another architecture?)");
  // State-dict-like initializer names ("<module>.weight") that the file does carry must sit where the
  // order puts them.
  std::map<std::string, size_t> position;
  for (size_t i = 0; i < conv_modules.size(); ++i) position[conv_modules[i]] = i;

  TensorMap out;
  for (size_t i = 0; i < convs.size(); ++i) {
    const OnnxNode& node = *convs[i];
    const std::string& module = conv_modules[i];
    const std::string where =
        source + ": Conv node " + std::to_string(i) + " ('" + node.name + "', the network's " + module + ")";
    require(node.inputs.size() >= 2, where + " has no weight input");
    for (size_t k = 1; k < node.inputs.size() && k < 3; ++k) {
      const std::string& input = node.inputs[k];
      const char* suffix = k == 1 ? ".weight" : ".bias";
      auto it = graph.initializers.find(input);
      require(it != graph.initializers.end(),
              where + ": its " + std::string(suffix + 1) + " '" + input + "' is not an initializer");
      if (ends_with(input, suffix)) {
        const std::string named = input.substr(0, input.size() - std::strlen(suffix));
        require(!position.count(named) || named == module,
                where + ": its " + std::string(suffix + 1) + " is named '" + input +
                    "', which belongs to another layer (a file of another architecture?)");
      }
      out[module + suffix] = it->second;
    }
  }
  return out;
}

std::vector<std::string> conv_module_names(torch::nn::Module& module) {
  std::vector<std::string> names;
  for (const auto& item : module.named_modules("", /*include_self=*/false)) {
    const auto params = item.value()->named_parameters(/*recurse=*/false);
    const torch::Tensor* w = params.find("weight");
    if (w && w->dim() == 4) names.push_back(item.key());
  }
  return names;
}

}  // namespace u3d::nn
