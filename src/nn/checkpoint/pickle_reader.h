#pragma once
// A restricted Python pickle reader for the pickles inside torch.save files. It is a small stack
// machine over the opcodes torch.save emits (protocol 2, plus the protocol 4 framing/memo forms) and
// never runs code: every GLOBAL goes through PickleHooks, which decides whether the name is one it
// knows and builds the object itself. Anything else (unknown opcodes, unknown globals, malformed or
// truncated data, a result that contains itself) is a u3d::Error naming the source, the byte offset and
// the problem.
#include <concepts>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace u3d::nn::pickle {

struct Tuple;
struct List;
struct Dict;

// A module-level name the hooks accepted, e.g. {"collections", "OrderedDict"}.
struct Global {
  std::string module;
  std::string name;
  std::string qualified() const { return module + "." + name; }
};

// Objects the hooks build (storages, tensors): opaque to the reader.
struct Object {
  virtual ~Object() = default;
};

struct None {};

// Containers are shared pointers because the pickle memo aliases them: an item appended to a list
// after it was memoized must be visible through every reference.
struct Value {
  using Variant = std::variant<None, bool, int64_t, double, std::string, std::shared_ptr<Tuple>,
                               std::shared_ptr<List>, std::shared_ptr<Dict>, Global, std::shared_ptr<const Object>>;
  Variant v;

  Value() = default;
  template <class T>
    requires std::constructible_from<Variant, T&&>
  Value(T&& x) : v(std::forward<T>(x)) {}

  template <class T>
  bool is() const { return std::holds_alternative<T>(v); }
  template <class T>
  const T& as() const { return std::get<T>(v); }
  // Short description for error messages ("str", "tuple", "int", ...).
  std::string type_name() const;
};

// The destructors free nested containers in a loop, not recursively, so any depth is safe to free.
struct Tuple {
  std::vector<Value> items;
  ~Tuple();
};
struct List {
  std::vector<Value> items;
  ~List();
};
// dict / OrderedDict in insertion order.
struct Dict {
  std::vector<std::pair<Value, Value>> items;
  ~Dict();
};

class PickleHooks {
 public:
  virtual ~PickleHooks() = default;
  // Called for GLOBAL / STACK_GLOBAL. Throw u3d::Error for names that are not allowed.
  virtual void check_global(const Global& global) = 0;
  // REDUCE: global(*args). Only called with globals that passed check_global.
  virtual Value call(const Global& callable, const std::vector<Value>& args) = 0;
  // BINPERSID: the persistent id (torch: a tuple describing a storage record).
  virtual Value persistent_load(const Value& pid) = 0;
  // BUILD: obj.__setstate__(state). Returns the updated object.
  virtual Value build(const Value& obj, const Value& state) = 0;
};

// Runs the pickle in `data` and returns the object left by STOP. `source` names the data in errors
// (e.g. "model.pth:archive/data.pkl").
Value unpickle(std::string_view data, PickleHooks& hooks, const std::string& source);

}  // namespace u3d::nn::pickle
