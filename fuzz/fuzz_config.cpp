// libFuzzer target: model and scheduler config JSON (nn/checkpoint/config_json, nn/schedulers/
// scheduler_config), the JSON files users bring with their weights. The file is parsed by
// read_json_file, then every key is read with every ConfigReader getter (each may refuse the type
// with u3d::Error) and the whole object is parsed as a scheduler config. These sources need no libtorch
// and are compiled into the target directly (fuzz/CMakeLists.txt).
#include "fuzz_common.h"
#include "nn/checkpoint/config_json.h"
#include "nn/schedulers/scheduler_config.h"

using u3d::fuzz::expect_clean;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto path = u3d::fuzz::write_scratch_file("config.json", data, size);
  nlohmann::json json;
  try {
    json = u3d::nn::read_json_file(path);
  } catch (const u3d::Error&) {
    return 0;
  }
  expect_clean([&] { u3d::nn::parse_scheduler_config(json, "fuzz config"); });
  expect_clean([&] {
    u3d::nn::ConfigReader reader(json, "fuzz config");
    for (const auto& item : json.items()) {
      const std::string key = item.key();
      expect_clean([&] { reader.get_int(key, 0); });
      expect_clean([&] { reader.get_double(key, 0.0); });
      expect_clean([&] { reader.get_bool(key, false); });
      expect_clean([&] { reader.get_string(key, ""); });
      expect_clean([&] { reader.get_int_list(key); });
      expect_clean([&] { reader.get_double_list(key, {}); });
      expect_clean([&] { reader.get_string_list(key); });
      expect_clean([&] { reader.get_int_or_list(key, 1, 4); });
      expect_clean([&] { reader.require_value(key, 1); });
      expect_clean([&] { reader.require_value(key, "linear"); });
    }
  });
  return 0;
}
