// libFuzzer target: the restricted pickle machine of .pth checkpoints (nn/checkpoint/pickle_reader).
// The input is the pickle itself (a zip's data.pkl). The hooks stand in for pth_reader's state-dict
// hooks, which need libtorch: they accept the same globals (OrderedDict, _rebuild_tensor_v2 /
// _rebuild_parameter, torch.<T>Storage) and build opaque objects, so the opcodes, stack, marks and
// memo are exercised as on real files. pickle_reader.cpp needs no libtorch and is compiled into the
// target directly (fuzz/CMakeLists.txt).
#include <set>

#include "fuzz_common.h"
#include "nn/checkpoint/pickle_reader.h"

namespace {

using namespace u3d::nn::pickle;

struct Opaque : Object {};

class FuzzHooks : public PickleHooks {
 public:
  void check_global(const Global& g) override {
    static const std::set<std::pair<std::string, std::string>> allowed = {
        {"collections", "OrderedDict"}, {"torch._utils", "_rebuild_tensor_v2"}, {"torch._utils", "_rebuild_parameter"},
        {"torch", "FloatStorage"},      {"torch", "HalfStorage"},               {"torch", "LongStorage"}};
    u3d::require(allowed.count({g.module, g.name}) > 0, "refused global " + g.qualified());
  }
  Value call(const Global& g, const std::vector<Value>& args) override {
    if (g.name == "OrderedDict") {
      u3d::require(args.empty(), "OrderedDict with arguments");
      return std::make_shared<Dict>();
    }
    if (g.name == "_rebuild_parameter") {
      u3d::require(args.size() == 3, "malformed _rebuild_parameter");
      return args[0];
    }
    u3d::require(g.name == "_rebuild_tensor_v2" && (args.size() == 6 || args.size() == 7), "bad call " + g.qualified());
    return std::shared_ptr<const Object>(std::make_shared<Opaque>());
  }
  Value persistent_load(const Value& pid) override {
    u3d::require(pid.is<std::shared_ptr<Tuple>>(), "persistent id is a " + pid.type_name());
    return std::shared_ptr<const Object>(std::make_shared<Opaque>());
  }
  Value build(const Value& obj, const Value&) override {
    u3d::require(obj.is<std::shared_ptr<Dict>>(), "BUILD on a " + obj.type_name());
    return obj;
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzHooks hooks;
  u3d::fuzz::expect_clean([&] {
    Value result = unpickle(std::string_view(reinterpret_cast<const char*>(data), size), hooks, "fuzz.pkl");
    (void)result.type_name();
  });
  return 0;
}
