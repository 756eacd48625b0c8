#include "nn/checkpoint/pickle_reader.h"

#include <bit>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "core/error.h"

namespace u3d::nn::pickle {

std::string Value::type_name() const {
  struct Namer {
    std::string operator()(const None&) const { return "None"; }
    std::string operator()(bool) const { return "bool"; }
    std::string operator()(int64_t) const { return "int"; }
    std::string operator()(double) const { return "float"; }
    std::string operator()(const std::string&) const { return "str"; }
    std::string operator()(const std::shared_ptr<Tuple>&) const { return "tuple"; }
    std::string operator()(const std::shared_ptr<List>&) const { return "list"; }
    std::string operator()(const std::shared_ptr<Dict>&) const { return "dict"; }
    std::string operator()(const Global& g) const { return "global " + g.qualified(); }
    std::string operator()(const std::shared_ptr<const Object>&) const { return "object"; }
  };
  return std::visit(Namer{}, v);
}

namespace {

// Opcodes of the pickle protocol (Python's Lib/pickle.py names).
enum Op : uint8_t {
  MARK = '(',
  STOP = '.',
  POP = '0',
  POP_MARK = '1',
  DUP = '2',
  BININT = 'J',
  BININT1 = 'K',
  BININT2 = 'M',
  NONE = 'N',
  BINPERSID = 'Q',
  REDUCE = 'R',
  BINUNICODE = 'X',
  EMPTY_LIST = ']',
  APPEND = 'a',
  BUILD = 'b',
  GLOBAL = 'c',
  DICT = 'd',
  APPENDS = 'e',
  BINGET = 'h',
  LONG_BINGET = 'j',
  LIST = 'l',
  BINPUT = 'q',
  LONG_BINPUT = 'r',
  SETITEM = 's',
  TUPLE = 't',
  SETITEMS = 'u',
  EMPTY_DICT = '}',
  EMPTY_TUPLE = ')',
  BINFLOAT = 'G',
  PROTO = 0x80,
  TUPLE1 = 0x85,
  TUPLE2 = 0x86,
  TUPLE3 = 0x87,
  NEWTRUE = 0x88,
  NEWFALSE = 0x89,
  LONG1 = 0x8a,
  SHORT_BINUNICODE = 0x8c,
  BINUNICODE8 = 0x8d,
  STACK_GLOBAL = 0x93,
  MEMOIZE = 0x94,
  FRAME = 0x95,
};

// The identity of a container value; nullptr for every other value.
const void* container_id(const Value& v) {
  if (const auto* t = std::get_if<std::shared_ptr<Tuple>>(&v.v)) return t->get();
  if (const auto* l = std::get_if<std::shared_ptr<List>>(&v.v)) return l->get();
  if (const auto* d = std::get_if<std::shared_ptr<Dict>>(&v.v)) return d->get();
  return nullptr;
}

// The values directly inside a container (dict keys and values alike).
std::vector<Value*> children_of(const Value& v) {
  std::vector<Value*> out;
  auto add = [&](std::vector<Value>& items) {
    for (Value& item : items) out.push_back(&item);
  };
  if (const auto* t = std::get_if<std::shared_ptr<Tuple>>(&v.v)) add((*t)->items);
  if (const auto* l = std::get_if<std::shared_ptr<List>>(&v.v)) add((*l)->items);
  if (const auto* d = std::get_if<std::shared_ptr<Dict>>(&v.v))
    for (auto& [key, value] : (*d)->items) out.insert(out.end(), {&key, &value});
  return out;
}

class Machine {
 public:
  Machine(std::string_view data, PickleHooks& hooks, const std::string& source)
      : data_(data), hooks_(hooks), source_(source) {}
  Machine(const Machine&) = delete;
  Machine& operator=(const Machine&) = delete;
  ~Machine() { release(); }

  Value run() {
    while (true) {
      op_offset_ = pos_;
      const uint8_t op = read_u8();
      switch (op) {
        case PROTO: {
          const uint8_t proto = read_u8();
          if (proto > 5) fail("unsupported pickle protocol " + std::to_string(proto));
          break;
        }
        case FRAME: read_bytes(8); break;  // framing is a streaming hint only
        case STOP: {
          if (stack_.size() != 1 || !marks_.empty()) fail("STOP with " + std::to_string(stack_.size()) + " values on the stack");
          check_result(stack_.back());
          return stack_.back();
        }
        case MARK: marks_.push_back(stack_.size()); break;
        case POP: pop(); break;
        case POP_MARK: pop_mark(); break;
        case DUP: stack_.push_back(top()); break;
        case NONE: push(None{}); break;
        case NEWTRUE: push(true); break;
        case NEWFALSE: push(false); break;
        case BININT: push(int64_t(int32_t(read_le(4)))); break;
        case BININT1: push(int64_t(read_le(1))); break;
        case BININT2: push(int64_t(read_le(2))); break;
        case LONG1: push(read_long(read_u8())); break;
        case BINFLOAT: {
          uint64_t bits = 0;
          for (char c : read_bytes(8)) bits = (bits << 8) | uint8_t(c);  // big-endian
          push(std::bit_cast<double>(bits));
          break;
        }
        case SHORT_BINUNICODE: push(std::string(read_bytes(read_u8()))); break;
        case BINUNICODE: push(std::string(read_bytes(read_le(4)))); break;
        case BINUNICODE8: push(std::string(read_bytes(read_le(8)))); break;
        case EMPTY_TUPLE: push(std::make_shared<Tuple>()); break;
        case TUPLE: push(std::make_shared<Tuple>(Tuple{pop_mark()})); break;
        case TUPLE1:
        case TUPLE2:
        case TUPLE3: {
          const size_t n = op - TUPLE1 + 1;
          if (stack_.size() < stack_floor() + n) fail("tuple of " + std::to_string(n) + " needs more stack values");
          auto tuple = std::make_shared<Tuple>(Tuple{{stack_.end() - n, stack_.end()}});
          stack_.resize(stack_.size() - n);
          push(std::move(tuple));
          break;
        }
        case EMPTY_LIST: push(std::make_shared<List>()); break;
        case LIST: push(std::make_shared<List>(List{pop_mark()})); break;
        case APPEND: {
          Value item = pop();
          list_at_top().items.push_back(std::move(item));
          break;
        }
        case APPENDS: {
          std::vector<Value> items = pop_mark();
          List& list = list_at_top();
          list.items.insert(list.items.end(), items.begin(), items.end());
          break;
        }
        case EMPTY_DICT: push(std::make_shared<Dict>()); break;
        case DICT: {
          auto dict = std::make_shared<Dict>();
          set_items(*dict, pop_mark());
          push(std::move(dict));
          break;
        }
        case SETITEM: {
          Value value = pop();
          Value key = pop();
          set_items(dict_at_top(), {std::move(key), std::move(value)});
          break;
        }
        case SETITEMS: {
          std::vector<Value> items = pop_mark();
          set_items(dict_at_top(), items);
          break;
        }
        case BINPUT: memo_[uint32_t(read_le(1))] = top(); break;
        case LONG_BINPUT: memo_[uint32_t(read_le(4))] = top(); break;
        case MEMOIZE: memo_[uint32_t(memo_.size())] = top(); break;
        case BINGET: push(memo_get(uint32_t(read_le(1)))); break;
        case LONG_BINGET: push(memo_get(uint32_t(read_le(4)))); break;
        case GLOBAL: {
          std::string module = read_line();
          std::string name = read_line();
          push_global(Global{std::move(module), std::move(name)});
          break;
        }
        case STACK_GLOBAL: {
          Value name = pop();
          Value module = pop();
          if (!module.is<std::string>() || !name.is<std::string>()) fail("STACK_GLOBAL needs two strings");
          push_global(Global{module.as<std::string>(), name.as<std::string>()});
          break;
        }
        case REDUCE: {
          Value args = pop();
          Value callable = pop();
          if (!callable.is<Global>()) fail("REDUCE on a " + callable.type_name() + ", expected a global");
          if (!args.is<std::shared_ptr<Tuple>>()) fail("REDUCE arguments are a " + args.type_name() + ", expected a tuple");
          push(hooks_.call(callable.as<Global>(), args.as<std::shared_ptr<Tuple>>()->items));
          break;
        }
        case BINPERSID: push(hooks_.persistent_load(pop())); break;
        case BUILD: {
          Value state = pop();
          Value obj = pop();
          push(hooks_.build(obj, state));
          break;
        }
        default: {
          std::ostringstream hex;
          hex << "0x" << std::hex << int(op);
          fail("unsupported pickle opcode " + hex.str() + " (not written by torch.save)");
        }
      }
    }
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(source_ + ": invalid or unsupported pickle at byte " + std::to_string(op_offset_) + ": " + what);
  }

  std::string_view read_bytes(uint64_t n) {
    if (n > data_.size() - pos_) fail("truncated (needs " + std::to_string(n) + " more bytes)");
    std::string_view out = data_.substr(pos_, n);
    pos_ += n;
    return out;
  }
  uint8_t read_u8() { return uint8_t(read_bytes(1)[0]); }
  uint64_t read_le(int n) {
    std::string_view b = read_bytes(n);
    uint64_t v = 0;
    for (int i = n - 1; i >= 0; --i) v = (v << 8) | uint8_t(b[i]);
    return v;
  }
  // LONG1: little-endian two's complement of n bytes. Values beyond int64 never occur in state dicts.
  int64_t read_long(uint8_t n) {
    if (n == 0) return 0;
    if (n > 8) fail("integer of " + std::to_string(n) + " bytes does not fit in 64 bits");
    uint64_t v = read_le(n);
    if (n < 8 && (v >> (8 * n - 1)) & 1) v |= ~uint64_t(0) << (8 * n);  // sign-extend
    return int64_t(v);
  }
  std::string read_line() {
    const size_t end = data_.find('\n', pos_);
    if (end == std::string_view::npos) fail("truncated GLOBAL name");
    std::string line(data_.substr(pos_, end - pos_));
    pos_ = end + 1;
    return line;
  }

  void push(Value v) { stack_.push_back(std::move(v)); }
  size_t stack_floor() const { return marks_.empty() ? 0 : marks_.back(); }
  const Value& top() const {
    if (stack_.size() <= stack_floor()) fail("stack underflow");
    return stack_.back();
  }
  Value pop() {
    if (stack_.size() <= stack_floor()) fail("stack underflow");
    Value v = std::move(stack_.back());
    stack_.pop_back();
    return v;
  }
  std::vector<Value> pop_mark() {
    if (marks_.empty()) fail("missing MARK");
    const size_t mark = marks_.back();
    marks_.pop_back();
    std::vector<Value> items(std::make_move_iterator(stack_.begin() + mark), std::make_move_iterator(stack_.end()));
    stack_.resize(mark);
    return items;
  }
  List& list_at_top() {
    const Value& v = top();
    if (!v.is<std::shared_ptr<List>>()) fail("append to a " + v.type_name() + ", expected a list");
    return *v.as<std::shared_ptr<List>>();
  }
  Dict& dict_at_top() {
    const Value& v = top();
    if (!v.is<std::shared_ptr<Dict>>()) fail("setitem on a " + v.type_name() + ", expected a dict");
    return *v.as<std::shared_ptr<Dict>>();
  }
  // Keys are compared only when they are strings (the only keys state dicts use); a repeated key
  // replaces the earlier value, as in Python.
  void set_items(Dict& dict, const std::vector<Value>& items) {
    if (items.size() % 2 != 0) fail("odd number of dict items");
    for (size_t i = 0; i < items.size(); i += 2) {
      const Value& key = items[i];
      bool replaced = false;
      if (key.is<std::string>()) {
        for (auto& [k, v] : dict.items) {
          if (k.is<std::string>() && k.as<std::string>() == key.as<std::string>()) {
            v = items[i + 1];
            replaced = true;
            break;
          }
        }
      }
      if (!replaced) dict.items.emplace_back(key, items[i + 1]);
    }
  }
  Value memo_get(uint32_t index) const {
    auto it = memo_.find(index);
    if (it == memo_.end()) fail("memo entry " + std::to_string(index) + " was never stored");
    return it->second;
  }
  void push_global(Global global) {
    hooks_.check_global(global);
    push(std::move(global));
  }

  // The result must not contain itself: APPEND / SETITEM through the memo can put a container inside
  // itself, which the shared pointers would never free (and no state dict does). An iterative
  // depth-first walk; every container it finishes goes into `kept_`, which release() leaves alone.
  void check_result(const Value& result) {
    struct Frame {
      const void* id;
      std::vector<Value*> children;
      size_t next = 0;
    };
    std::vector<Frame> path;
    std::unordered_set<const void*> on_path;
    auto enter = [&](const Value& v) {
      const void* id = container_id(v);
      if (!id || kept_.count(id)) return;
      if (!on_path.insert(id).second) {
        kept_.clear();
        fail("the result contains itself (a recursive structure; state dicts have none)");
      }
      path.push_back({id, children_of(v)});
    };
    enter(result);
    while (!path.empty()) {
      Frame& frame = path.back();
      if (frame.next < frame.children.size()) {
        enter(*frame.children[frame.next++]);  // may grow `path`: `frame` is not used after this
        continue;
      }
      on_path.erase(frame.id);
      kept_.insert(frame.id);
      path.pop_back();
    }
  }

  // Empties every container that is not part of the returned result: this breaks the reference cycles
  // left on the stack or in the memo, or in a rejected result. After a failure nothing is kept.
  void release() {
    std::vector<Value> work;
    for (Value& v : stack_) work.push_back(std::move(v));
    for (auto& entry : memo_) work.push_back(std::move(entry.second));
    stack_.clear();
    memo_.clear();
    while (!work.empty()) {
      Value v = std::move(work.back());
      work.pop_back();
      const void* id = container_id(v);
      if (!id || kept_.count(id)) continue;
      for (Value* child : children_of(v)) work.push_back(std::move(*child));
      if (auto* t = std::get_if<std::shared_ptr<Tuple>>(&v.v)) (*t)->items.clear();
      if (auto* l = std::get_if<std::shared_ptr<List>>(&v.v)) (*l)->items.clear();
      if (auto* d = std::get_if<std::shared_ptr<Dict>>(&v.v)) (*d)->items.clear();
    }
  }

  std::string_view data_;
  PickleHooks& hooks_;
  const std::string& source_;
  size_t pos_ = 0;
  size_t op_offset_ = 0;
  std::vector<Value> stack_;
  std::vector<size_t> marks_;
  std::unordered_map<uint32_t, Value> memo_;
  std::unordered_set<const void*> kept_;  // the containers of the returned result
};

}  // namespace

// A container's items are moved out before the container itself is freed, and containers that the
// items alone keep alive are emptied the same way, so nesting of any depth (one byte per level: TUPLE1
// after TUPLE1) is freed in a loop instead of a recursion that overflows the stack.
static void free_items_iteratively(std::vector<Value>& items) {
  std::vector<Value> work(std::make_move_iterator(items.begin()), std::make_move_iterator(items.end()));
  items.clear();
  while (!work.empty()) {
    Value v = std::move(work.back());
    work.pop_back();
    auto take = [&](auto& container) {
      if (!container || container.use_count() != 1) return;  // still used elsewhere: not freed now
      for (Value* child : children_of(v)) work.push_back(std::move(*child));
      container->items.clear();
    };
    if (auto* t = std::get_if<std::shared_ptr<Tuple>>(&v.v)) take(*t);
    if (auto* l = std::get_if<std::shared_ptr<List>>(&v.v)) take(*l);
    if (auto* d = std::get_if<std::shared_ptr<Dict>>(&v.v)) take(*d);
  }
}

Tuple::~Tuple() { free_items_iteratively(items); }
List::~List() { free_items_iteratively(items); }
Dict::~Dict() {
  std::vector<Value> flat;
  for (auto& [key, value] : items) flat.insert(flat.end(), {std::move(key), std::move(value)});
  items.clear();
  free_items_iteratively(flat);
}

Value unpickle(std::string_view data, PickleHooks& hooks, const std::string& source) {
  return Machine(data, hooks, source).run();
}

}  // namespace u3d::nn::pickle
