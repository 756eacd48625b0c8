#pragma once
// Assembles the pickle bytes of a torch.save state dict (protocol 2), opcode by opcode: what
// pth_writer.h writes, and what tests use to hand-craft unusual files for the reader (pickle_reader.h).
// Opcode names as in Python's pickletools.
#include <cstdint>
#include <string>
#include <vector>

namespace u3d::nn::pickle {

class PickleWriter {
 public:
  PickleWriter() { bytes_ += "\x80\x02"; }  // PROTO 2

  PickleWriter& op(char c) {
    bytes_ += c;
    return *this;
  }
  PickleWriter& mark() { return op('('); }
  PickleWriter& global(const std::string& module, const std::string& name) {
    bytes_ += 'c' + module + '\n' + name + '\n';
    return *this;
  }
  PickleWriter& str(const std::string& s) {  // BINUNICODE
    op('X');
    le(uint64_t(s.size()), 4);
    bytes_ += s;
    return *this;
  }
  PickleWriter& integer(int64_t v) {
    if (v >= INT32_MIN && v <= INT32_MAX) {
      op('J');  // BININT
      le(uint64_t(uint32_t(int32_t(v))), 4);
    } else {
      op('\x8a').op(char(8));  // LONG1, 8 bytes of two's complement
      le(uint64_t(v), 8);
    }
    return *this;
  }
  PickleWriter& int_tuple(const std::vector<int64_t>& values) {
    mark();
    for (int64_t v : values) integer(v);
    return op('t');
  }
  PickleWriter& empty_ordered_dict() { return global("collections", "OrderedDict").op(')').op('R'); }
  // _rebuild_tensor_v2(('storage', torch.<storage_type>, key, 'cpu', numel), offset, size, stride, False,
  // OrderedDict()): a tensor viewing storage record data/<key>.
  PickleWriter& tensor(const std::string& storage_type, const std::string& key, int64_t numel, int64_t offset,
                       const std::vector<int64_t>& sizes, const std::vector<int64_t>& strides) {
    global("torch._utils", "_rebuild_tensor_v2").mark();
    mark().str("storage").global("torch", storage_type).str(key).str("cpu").integer(numel).op('t').op('Q');
    integer(offset).int_tuple(sizes).int_tuple(strides).op('\x89').empty_ordered_dict();
    return op('t').op('R');
  }
  // The bytes with STOP appended.
  std::string finish() const { return bytes_ + "."; }

 private:
  void le(uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) bytes_ += char((v >> (8 * i)) & 0xff);
  }
  std::string bytes_;
};

}  // namespace u3d::nn::pickle
