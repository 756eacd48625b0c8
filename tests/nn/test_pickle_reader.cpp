// The pickle machine on its own (no libtorch): structures a state dict never has but a crafted file can
// build, a container inside itself and nesting far deeper than the stack allows to free recursively.
#include <gtest/gtest.h>

#include <string>

#include "core/error.h"
#include "nn/checkpoint/pickle_reader.h"

using namespace u3d::nn::pickle;

namespace {

// Accepts no globals: these pickles need none.
class NoGlobals : public PickleHooks {
 public:
  void check_global(const Global& g) override { throw u3d::Error("refused " + g.qualified()); }
  Value call(const Global&, const std::vector<Value>&) override { throw u3d::Error("call"); }
  Value persistent_load(const Value&) override { throw u3d::Error("persistent_load"); }
  Value build(const Value&, const Value&) override { throw u3d::Error("build"); }
};

Value run(const std::string& data) {
  NoGlobals hooks;
  return unpickle(data, hooks, "test.pkl");
}

void expect_error(const std::string& data, const std::string& expected) {
  try {
    Value v = run(data);
    ADD_FAILURE() << "accepted, result: " << v.type_name();
  } catch (const u3d::Error& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("test.pkl"), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(PickleReader, AResultThatContainsItselfIsAnError) {
  using namespace std::string_literals;
  // EMPTY_LIST, BINPUT 0, BINGET 0, APPEND, STOP: l = []; l.append(l)
  expect_error("]q\x00h\x00\x61."s, "contains itself");
  // d = {}; d[d] = d
  expect_error("}q\x00h\x00h\x00s."s, "contains itself");
  // l = []; l.append((l,))
  expect_error("]q\x00h\x00\x85\x61."s, "contains itself");
  // A cycle left in the memo does not matter when the result is fine (and is freed: LeakSanitizer).
  EXPECT_TRUE(run("]q\x00h\x00\x61\x30N."s).is<None>());
}

TEST(PickleReader, DeepNestingIsFreedWithoutRecursion) {
  // None wrapped in 200,000 one-item tuples (TUPLE1, one byte per level): freeing that recursively
  // overflows the stack.
  const std::string deep = "N" + std::string(200000, '\x85');
  Value v = run(deep + ".");
  ASSERT_TRUE(v.is<std::shared_ptr<Tuple>>());
  v = Value();  // freed here
  // The same nesting popped off the stack halfway through, then an error: freed as well.
  EXPECT_TRUE(run(deep + "0N.").is<None>());
  expect_error(deep + "\xff", "opcode 0xff");
}
