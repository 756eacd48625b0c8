// torch.save zip checkpoints: the golden unet_mv weights written by real torch.save, and small
// archives written here (caffe2's zip writer + a hand-assembled pickle) for the corner cases.
#include <caffe2/serialize/inline_container.h>
#include <gtest/gtest.h>
#include <libdeflate.h>

#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>
#include <unistd.h>

#include "core/error.h"
#include "nn/checkpoint/pickle_writer.h"
#include "nn/checkpoint/pth_reader.h"
#include "nn/checkpoint/safetensors.h"
#include "nn/checkpoint/weights_file.h"

namespace fs = std::filesystem;
using namespace u3d::nn;

namespace {

const fs::path kUnetMv = fs::path(UNIQUE3D_TEST_DATA) / "nn" / "unet_mv";

using pickle::PickleWriter;

class PthTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("u3d_pth_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes an archive "<name>.pth" holding data.pkl and the given storage records data/<key>.
  fs::path write_pth(const std::string& name, const std::string& pickle,
                     const std::map<std::string, std::string>& records) {
    const fs::path path = dir_ / (name + ".pth");
    caffe2::serialize::PyTorchStreamWriter writer(path.string());
    writer.writeRecord("data.pkl", pickle.data(), pickle.size());
    for (const auto& [key, bytes] : records) writer.writeRecord("data/" + key, bytes.data(), bytes.size());
    writer.writeEndOfFile();
    return path;
  }

  // The same archive as write_pth (plus a version record), assembled here with every record deflated,
  // as a checkpoint re-zipped by a zip tool would be; torch.save itself stores them.
  fs::path write_deflated_pth(const std::string& name, const std::string& pickle,
                              const std::map<std::string, std::string>& records) {
    std::map<std::string, std::string> entries = {{"data.pkl", pickle}, {"version", "3\n"}};
    for (const auto& [key, bytes] : records) entries["data/" + key] = bytes;
    std::string out, directory;
    auto put = [](std::string& to, uint64_t value, int bytes) {
      for (int i = 0; i < bytes; ++i) to.push_back(char((value >> (8 * i)) & 0xff));
    };
    libdeflate_compressor* compressor = libdeflate_alloc_compressor(6);
    for (const auto& [entry, bytes] : entries) {
      std::string packed(libdeflate_deflate_compress_bound(compressor, bytes.size()), '\0');
      packed.resize(libdeflate_deflate_compress(compressor, bytes.data(), bytes.size(), packed.data(), packed.size()));
      const std::string full = name + "/" + entry;
      const uint32_t crc = libdeflate_crc32(0, bytes.data(), bytes.size());
      const uint64_t local = out.size();
      for (std::string* header : {&out, &directory}) {
        const bool central = header == &directory;
        put(*header, central ? 0x02014b50 : 0x04034b50, 4);
        if (central) put(*header, 20, 2);  // version made by
        for (uint64_t v : {20, 0, 8, 0, 0}) put(*header, v, 2);  // version needed, flags, deflate, time, date
        put(*header, crc, 4);
        put(*header, packed.size(), 4);
        put(*header, bytes.size(), 4);
        put(*header, full.size(), 2);
        put(*header, 0, 2);  // extra field
        if (central) {
          for (int v = 0; v < 3; ++v) put(*header, 0, 2);  // comment, disk, internal attributes
          put(*header, 0, 4);                              // external attributes
          put(*header, local, 4);
        }
        *header += full;
        if (!central) out += packed;
      }
    }
    libdeflate_free_compressor(compressor);
    const uint64_t directory_offset = out.size();
    out += directory;
    put(out, 0x06054b50, 4);
    put(out, 0, 4);  // disk numbers
    put(out, entries.size(), 2);
    put(out, entries.size(), 2);
    put(out, directory.size(), 4);
    put(out, directory_offset, 4);
    put(out, 0, 2);
    const fs::path path = dir_ / (name + ".pth");
    std::ofstream(path, std::ios::binary).write(out.data(), std::streamsize(out.size()));
    return path;
  }

  static std::string raw_bytes(const torch::Tensor& t) {
    const torch::Tensor c = t.contiguous();
    return std::string(static_cast<const char*>(c.data_ptr()), c.nbytes());
  }

  static void expect_error(const fs::path& path, std::initializer_list<std::string> fragments) {
    try {
      load_pth(path);
      ADD_FAILURE() << "no error for " << path;
    } catch (const u3d::Error& e) {
      const std::string msg = e.what();
      for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << "'" << f << "' not in: " << msg;
    }
  }

  fs::path dir_;
};

}  // namespace

// The acceptance check: the same state dict saved by torch.save and as safetensors loads identically.
TEST_F(PthTest, GoldenPthEqualsSafetensors) {
  const TensorMap from_pth = load_pth(kUnetMv / "weights.pth");
  const TensorMap from_st = load_safetensors(kUnetMv / "weights.safetensors");
  ASSERT_EQ(from_pth.size(), from_st.size());
  ASSERT_GT(from_pth.size(), 100u);
  for (const auto& [name, expected] : from_st) {
    auto it = from_pth.find(name);
    ASSERT_NE(it, from_pth.end()) << name;
    EXPECT_EQ(it->second.scalar_type(), expected.scalar_type()) << name;
    EXPECT_EQ(it->second.sizes(), expected.sizes()) << name;
    EXPECT_TRUE(torch::equal(it->second, expected)) << name;
  }
  // Format detection by content, whatever the extension.
  EXPECT_EQ(load_weights(kUnetMv / "weights.pth").size(), from_st.size());
  EXPECT_EQ(load_weights(kUnetMv / "weights.safetensors").size(), from_st.size());
}

TEST_F(PthTest, DtypesOffsetsStridesAndSharedStorage) {
  const torch::Tensor base = torch::arange(24, torch::kFloat32);
  const torch::Tensor bf16 = torch::linspace(-3, 3, 6).to(torch::kBFloat16);
  const torch::Tensor f16 = torch::linspace(-1, 1, 5).to(torch::kFloat16);
  const torch::Tensor i64 = torch::tensor({int64_t(1) << 40, int64_t(-7)});
  const torch::Tensor flags = torch::tensor({true, false, true});
  PickleWriter p;
  p.empty_ordered_dict().mark();
  p.str("matrix").tensor("FloatStorage", "0", 24, 0, {4, 6}, {6, 1});
  p.str("transposed").tensor("FloatStorage", "0", 24, 0, {6, 4}, {1, 6});  // same storage, non-contiguous view
  p.str("slice").tensor("FloatStorage", "0", 24, 7, {2, 3}, {6, 2});       // offset + strided
  p.str("bf16").tensor("BFloat16Storage", "1", 6, 0, {2, 3}, {3, 1});
  p.str("f16").tensor("HalfStorage", "2", 5, 0, {5}, {1});
  p.str("i64").tensor("LongStorage", "3", 2, 0, {2}, {1});
  p.str("flags").tensor("BoolStorage", "4", 3, 0, {3}, {1});
  p.str("scalar").tensor("FloatStorage", "0", 24, 5, {}, {});
  p.str("param").global("torch._utils", "_rebuild_parameter").mark();
  p.tensor("FloatStorage", "0", 24, 0, {24}, {1}).op('\x88').empty_ordered_dict().op('t').op('R');
  p.op('u').op('}').op('b');  // SETITEMS, then BUILD with an (ignored) state, as torch writes _metadata
  const fs::path path = write_pth("mixed", p.finish(),
                                  {{"0", raw_bytes(base)}, {"1", raw_bytes(bf16)}, {"2", raw_bytes(f16)},
                                   {"3", raw_bytes(i64)}, {"4", raw_bytes(flags)}});
  const TensorMap m = load_pth(path);
  ASSERT_EQ(m.size(), 9u);
  EXPECT_TRUE(torch::equal(m.at("matrix"), base.view({4, 6})));
  EXPECT_TRUE(torch::equal(m.at("transposed"), base.view({4, 6}).t()));
  EXPECT_FALSE(m.at("transposed").is_contiguous());
  EXPECT_TRUE(torch::equal(m.at("slice"), base.view({4, 6}).slice(0, 1, 3).slice(1, 1, 6, 2)));
  EXPECT_TRUE(m.at("matrix").is_alias_of(m.at("transposed")));  // one storage, read once
  EXPECT_TRUE(torch::equal(m.at("bf16"), bf16.view({2, 3})));
  EXPECT_EQ(m.at("bf16").scalar_type(), torch::kBFloat16);
  EXPECT_TRUE(torch::equal(m.at("f16"), f16));
  EXPECT_TRUE(torch::equal(m.at("i64"), i64));
  EXPECT_TRUE(torch::equal(m.at("flags"), flags));
  EXPECT_EQ(m.at("scalar").dim(), 0);
  EXPECT_EQ(m.at("scalar").item<float>(), 5.0f);
  EXPECT_TRUE(torch::equal(m.at("param"), base));
}

TEST_F(PthTest, RefusesGlobalsOutsideTheWhitelist) {
  for (const auto& [module, name] : std::vector<std::pair<std::string, std::string>>{
           {"os", "system"}, {"torch.storage", "_load_from_bytes"}, {"builtins", "eval"}}) {
    PickleWriter p;
    p.global(module, name).mark().str("echo hi").op('t').op('R');
    expect_error(write_pth("evil", p.finish(), {}), {"evil.pth", module + "." + name, "refuses"});
  }
}

// Loading never runs code from the file: every way a pickle can name a callable goes through the
// whitelist or is not understood at all. Each pickle would run `touch ran` if anything ran it.
TEST_F(PthTest, HostilePicklesAreRefusedAndRunNothing) {
  const std::string command = "touch " + (dir_ / "ran").string();
  auto raw = [](PickleWriter& p, const std::string& bytes) -> PickleWriter& {
    for (char c : bytes) p.op(c);
    return p;
  };
  PickleWriter stack_global;  // protocol 4's STACK_GLOBAL: module and name from the stack
  stack_global.str("os").str("system").op('\x93').mark().str(command).op('t').op('R');
  expect_error(write_pth("stack_global", stack_global.finish(), {}), {"stack_global.pth", "'os.system'", "refuses"});

  PickleWriter getattr;  // the usual first step towards anything else
  getattr.global("builtins", "getattr").mark().str("os").str("system").op('t').op('R');
  expect_error(write_pth("getattr", getattr.finish(), {}), {"getattr.pth", "'builtins.getattr'", "refuses"});

  PickleWriter nested;  // an allowed call whose argument is a call of a refused one
  nested.global("collections", "OrderedDict").mark();
  nested.global("posix", "system").mark().str(command).op('t').op('R').op('t').op('R');
  expect_error(write_pth("nested", nested.finish(), {}), {"nested.pth", "'posix.system'", "refuses"});

  PickleWriter not_callable;  // REDUCE on a value that is not a global
  not_callable.str("os.system").mark().str(command).op('t').op('R');
  expect_error(write_pth("not_callable", not_callable.finish(), {}), {"not_callable.pth", "REDUCE on a"});

  PickleWriter inst;  // INST: import and call in one opcode
  raw(inst.mark().str(command).op('i'), "os\nsystem\n");
  expect_error(write_pth("inst", inst.finish(), {}), {"inst.pth", "opcode 0x69"});

  PickleWriter newobj;  // NEWOBJ: cls.__new__(cls, *args) of an allowed class
  newobj.global("collections", "OrderedDict").op(')').op('\x81');
  expect_error(write_pth("newobj", newobj.finish(), {}), {"newobj.pth", "opcode 0x81"});

  EXPECT_FALSE(fs::exists(dir_ / "ran"));
}

// Memo indices are 32-bit keys of a map: the largest is stored and read back without allocating
// anything for the indices below it; an index never stored is an error.
TEST_F(PthTest, HugeMemoIndices) {
  const std::string biggest("\xff\xff\xff\xff", 4), unset("\xfe\xff\xff\xff", 4);
  PickleWriter stored;
  stored.empty_ordered_dict().op('r');  // LONG_BINPUT 2^32 - 1
  for (char c : biggest) stored.op(c);
  stored.op('0').op('j');  // POP, LONG_BINGET 2^32 - 1
  for (char c : biggest) stored.op(c);
  EXPECT_TRUE(load_pth(write_pth("memo", stored.finish(), {})).empty());

  PickleWriter missing;
  missing.op('j');
  for (char c : unset) missing.op(c);
  expect_error(write_pth("missing_memo", missing.finish(), {}), {"missing_memo.pth", "memo entry 4294967294"});
}

// The zip directory of a crafted archive: a record placed past the end of the file, and two records
// pointing at the same bytes (overlapping); each is refused, naming the file.
TEST_F(PthTest, ZipRecordsOutsideTheFileOrOverlappingAreRefused) {
  const torch::Tensor a = torch::arange(16, torch::kFloat32), b = torch::arange(16, torch::kFloat32) * 2;
  PickleWriter p;
  p.empty_ordered_dict().mark();
  p.str("a").tensor("FloatStorage", "0", 16, 0, {16}, {1});
  p.str("b").tensor("FloatStorage", "1", 16, 0, {16}, {1}).op('u');
  // The central-directory entry of data/<key>: its local header offset is at byte 42.
  auto patch_offset = [&](const fs::path& path, const std::string& key, std::function<uint32_t(const std::string&)> offset) {
    std::string bytes;
    {
      std::ifstream in(path, std::ios::binary);
      bytes.assign((std::istreambuf_iterator<char>(in)), {});
    }
    auto entry_of = [&](const std::string& k) {
      const std::string name = "/data/" + k;
      for (size_t at = bytes.find("PK\x01\x02"); at != std::string::npos; at = bytes.find("PK\x01\x02", at + 4)) {
        const size_t len = uint8_t(bytes[at + 28]) | (uint8_t(bytes[at + 29]) << 8);
        const std::string entry_name = bytes.substr(at + 46, len);
        if (entry_name.size() >= name.size() && entry_name.compare(entry_name.size() - name.size(), name.size(), name) == 0)
          return at;
      }
      ADD_FAILURE() << "no directory entry for data/" << k;
      return std::string::npos;
    };
    const size_t at = entry_of(key);
    if (at == std::string::npos) return;
    const uint32_t v = offset(bytes.substr(entry_of("0"), 46));
    for (int i = 0; i < 4; ++i) bytes[at + 42 + i] = char((v >> (8 * i)) & 0xff);
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
  };
  const std::map<std::string, std::string> records{{"0", raw_bytes(a)}, {"1", raw_bytes(b)}};

  const fs::path past = write_pth("past_end", p.finish(), records);
  patch_offset(past, "1", [&](const std::string&) { return uint32_t(fs::file_size(past) + 1000); });
  expect_error(past, {"past_end.pth", "corrupt"});

  const fs::path overlap = write_pth("overlap", p.finish(), records);
  patch_offset(overlap, "1", [](const std::string& entry0) {
    return uint32_t(uint8_t(entry0[42]) | (uint8_t(entry0[43]) << 8) | (uint8_t(entry0[44]) << 16) |
                    (uint32_t(uint8_t(entry0[45])) << 24));
  });
  expect_error(overlap, {"overlap.pth", "corrupt"});
}

// Archives that break torch.save's layout are refused by the reader's check of the zip directory before
// any record is read: each edit below renames entries of a well-formed archive, in its central directory,
// its local headers, or both.
TEST_F(PthTest, ArchivesOutsideTorchSaveLayoutAreRefused) {
  PickleWriter p;
  p.empty_ordered_dict().mark().str("a").tensor("FloatStorage", "0", 4, 0, {4}, {1});
  p.str("b").tensor("FloatStorage", "1", 4, 0, {4}, {1}).op('u');
  const std::map<std::string, std::string> records{{"0", std::string(16, '\0')}, {"1", std::string(16, '\0')}};
  // Writes the archive `name`.pth (whose folder is `name`), replacing `from` by `to` (same length) at the
  // given occurrences: 0 is the local header, 1 the central directory; {} is every occurrence.
  auto edited = [&](const std::string& name, const std::string& from, const std::string& to, std::vector<int> which) {
    const fs::path path = write_pth(name, p.finish(), records);
    std::string bytes;
    {
      std::ifstream in(path, std::ios::binary);
      bytes.assign((std::istreambuf_iterator<char>(in)), {});
    }
    std::vector<size_t> at;
    for (size_t pos = bytes.find(from); pos != std::string::npos; pos = bytes.find(from, pos + 1)) at.push_back(pos);
    EXPECT_EQ(at.size(), 2u) << from;  // one local header and one directory entry
    if (which.empty()) which = {0, 1};
    for (int k : which) bytes.replace(at.at(size_t(k)), from.size(), to);
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
    return path;
  };
  EXPECT_EQ(load_pth(edited("plain", "plain/data/1", "plain/data/1", {})).size(), 2u);  // the unedited archive loads
  expect_error(edited("folder", "folder/data/1", "folder_data/1", {}), {"folder.pth", "outside the folder folder/"});
  expect_error(edited("loose", "loose/data/1", "loose_data_1", {}),
               {"loose.pth", "loose_data_1 is not inside a folder"});
  expect_error(edited("twice", "twice/data/1", "twice/data/0", {}), {"twice.pth", "two entries named twice/data/0"});
  expect_error(edited("local", "local/data/1", "local/data/2", {0}),
               {"local.pth", "local/data/1 does not match its local header"});
  expect_error(edited("unversioned", "unversioned/version", "unversioned/vers1on", {}),
               {"unversioned.pth", "without a version record"});

  // A stored record whose directory entry claims 2 GB (found by fuzz_pth, when libtorch's zip reader
  // allocated the claimed size before reading): stored data is as long as its compressed size.
  const fs::path huge = write_pth("huge", p.finish(), records);
  std::string bytes;
  {
    std::ifstream in(huge, std::ios::binary);
    bytes.assign((std::istreambuf_iterator<char>(in)), {});
  }
  const size_t entry = bytes.rfind("huge/data/1") - 46;  // its central-directory entry
  ASSERT_EQ(bytes.compare(entry, 4, std::string("PK\x01\x02", 4)), 0);
  for (int i = 0; i < 4; ++i) bytes[entry + 24 + size_t(i)] = char(i == 3 ? 0x7f : 0xff);  // uncompressed size
  std::ofstream(huge, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
  expect_error(huge, {"huge.pth", "huge/data/1 claims 2147483647 bytes from 16"});
}

TEST_F(PthTest, TruncatedArchiveNamesTheFile) {
  std::ifstream in(kUnetMv / "weights.pth", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const fs::path path = dir_ / "truncated.pth";
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() / 2));
  expect_error(path, {"truncated.pth", "corrupt or truncated"});
}

// Every record's CRC is checked, so a damaged weight is not loaded silently.
TEST_F(PthTest, FlippedByteInAWeightFailsTheCrc) {
  const torch::Tensor w = torch::arange(64, torch::kFloat32);
  PickleWriter p;
  p.empty_ordered_dict().mark().str("proj.weight").tensor("FloatStorage", "0", 64, 0, {64}, {1}).op('u');
  const fs::path path = write_pth("flipped", p.finish(), {{"0", raw_bytes(w)}});
  EXPECT_TRUE(torch::equal(load_pth(path).at("proj.weight"), w));

  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(f)), {});
  const std::string needle = raw_bytes(w).substr(40, 16);  // a piece of the weight's bytes
  const size_t at = bytes.find(needle);
  ASSERT_NE(at, std::string::npos);
  f.seekp(std::streamoff(at + 3));
  f.put(char(bytes[at + 3] ^ 0x10));
  f.close();
  expect_error(path, {"flipped.pth", "proj.weight", "data/0", "CRC"});
}

TEST_F(PthTest, CorruptPickleIsAnError) {
  PickleWriter p;
  p.empty_ordered_dict().mark().str("w").op('\xff');
  expect_error(write_pth("badop", p.finish(), {}), {"badop.pth", "opcode 0xff"});

  PickleWriter q;
  q.empty_ordered_dict().mark().str("w").op('X');  // BINUNICODE cut short
  std::string truncated = q.finish();
  truncated.pop_back();
  expect_error(write_pth("cut", truncated, {}), {"cut.pth", "truncated"});
}

TEST_F(PthTest, StorageProblemsNameTheTensor) {
  PickleWriter small;
  small.empty_ordered_dict().mark().str("conv.weight").tensor("FloatStorage", "0", 16, 0, {16}, {1}).op('u');
  expect_error(write_pth("short", small.finish(), {{"0", std::string(32, '\0')}}),
               {"short.pth", "conv.weight", "32 bytes"});

  PickleWriter outside;
  outside.empty_ordered_dict().mark().str("conv.bias").tensor("FloatStorage", "0", 4, 2, {4}, {1}).op('u');
  expect_error(write_pth("outside", outside.finish(), {{"0", std::string(16, '\0')}}),
               {"outside.pth", "conv.bias", "past its storage"});

  PickleWriter absent;
  absent.empty_ordered_dict().mark().str("lost").tensor("FloatStorage", "9", 1, 0, {1}, {1}).op('u');
  expect_error(write_pth("absent", absent.finish(), {}), {"absent.pth", "lost", "data/9"});

  // One record named by two storages of different sizes (found by fuzz_state_dict): the second view would
  // need a larger storage than the record.
  PickleWriter reused;
  reused.empty_ordered_dict().mark().str("a").tensor("FloatStorage", "0", 4, 0, {4}, {1});
  reused.str("b").tensor("DoubleStorage", "0", 4, 0, {4}, {1}).op('u');
  expect_error(write_pth("reused", reused.finish(), {{"0", std::string(16, '\0')}}),
               {"reused.pth", "'b'", "data/0", "16 and 32 bytes"});

  PickleWriter not_tensor;
  not_tensor.empty_ordered_dict().mark().str("epoch").integer(3).op('u');
  expect_error(write_pth("epoch", not_tensor.finish(), {}), {"epoch.pth", "'epoch'", "not a tensor"});
}

TEST_F(PthTest, LegacyAndForeignFiles) {
  const fs::path legacy = dir_ / "legacy.pth";
  std::ofstream(legacy, std::ios::binary) << "\x80\x02\x8a\x0a" << std::string(20, '\0');
  expect_error(legacy, {"legacy.pth", "legacy"});
  const fs::path text = dir_ / "notes.pth";
  std::ofstream(text) << "hello world";
  expect_error(text, {"notes.pth", "not a PyTorch zip checkpoint"});
  expect_error(dir_ / "missing.pth", {"missing.pth"});
}

// basicsr's checkpoints (RealESRGAN_x4plus.pth) wrap the state dict: {"params_ema": OrderedDict(...)}.
TEST_F(PthTest, NestedStateDictKeysArePrefixed) {
  const torch::Tensor w = torch::arange(6, torch::kFloat32);
  PickleWriter p;
  p.op('}').mark().str("params_ema").empty_ordered_dict().mark();
  p.str("conv_first.weight").tensor("FloatStorage", "0", 6, 0, {2, 3}, {3, 1}).op('u');
  p.op('u');
  const TensorMap m = load_pth(write_pth("nested", p.finish(), {{"0", raw_bytes(w)}}));
  ASSERT_EQ(m.size(), 1u);
  EXPECT_TRUE(torch::equal(m.at("params_ema.conv_first.weight"), w.view({2, 3})));

  // Only one level: a dict inside the inner state dict is not a tensor.
  PickleWriter deeper;
  deeper.op('}').mark().str("params").op('}').mark().str("inner").op('}').op('u').op('u');
  expect_error(write_pth("deeper", deeper.finish(), {}), {"deeper.pth", "params.inner", "not a tensor"});
}

// torch.save stores its records; a checkpoint whose records were deflated by a zip tool loads the same.
TEST_F(PthTest, DeflatedRecordsLoadAsStoredOnes) {
  const torch::Tensor w = torch::arange(4096, torch::kFloat32).remainder(7);  // compresses well
  PickleWriter p;
  p.empty_ordered_dict().mark().str("proj.weight").tensor("FloatStorage", "0", 4096, 0, {64, 64}, {64, 1}).op('u');
  const std::string pickle = p.finish();
  const TensorMap stored = load_pth(write_pth("stored", pickle, {{"0", raw_bytes(w)}}));
  const fs::path deflated = write_deflated_pth("deflated", pickle, {{"0", raw_bytes(w)}});
  ASSERT_LT(fs::file_size(deflated), w.nbytes() / 4);
  const TensorMap m = load_pth(deflated);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_TRUE(torch::equal(m.at("proj.weight"), stored.at("proj.weight")));
  EXPECT_TRUE(torch::equal(m.at("proj.weight"), w.view({64, 64})));

  // A damaged deflate stream names the record and the tensor.
  std::fstream f(deflated, std::ios::in | std::ios::out | std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(f)), {});
  const size_t record = bytes.find("deflated/data/0");
  ASSERT_NE(record, std::string::npos);
  const size_t at = record + std::string("deflated/data/0").size() + 2;  // inside the compressed data
  f.seekp(std::streamoff(at));
  f.put(char(bytes[at] ^ 0x55));
  f.close();
  expect_error(deflated, {"deflated.pth", "proj.weight", "data/0"});
}

// Tensors are views of the mapped file, copied on write: writing to one changes neither the file nor
// a later load.
TEST_F(PthTest, LoadedTensorsAreTheProcesssOwnToWrite) {
  const torch::Tensor w = torch::arange(5000, torch::kFloat32);
  PickleWriter p;
  p.empty_ordered_dict().mark().str("w").tensor("FloatStorage", "0", 5000, 0, {5000}, {1}).op('u');
  const fs::path path = write_pth("writable", p.finish(), {{"0", raw_bytes(w)}});
  const auto size = fs::file_size(path);
  {
    TensorMap m = load_pth(path);
    m.at("w").fill_(-1.0f);
    EXPECT_EQ(m.at("w").sum().item<float>(), -5000.0f);
  }
  EXPECT_EQ(fs::file_size(path), size);
  EXPECT_TRUE(torch::equal(load_pth(path).at("w"), w));
}
