// ConfigReader: type checks of config.json values, including integral floats and values no int64 holds.
#include <gtest/gtest.h>

#include "core/error.h"
#include "nn/checkpoint/config_json.h"

using u3d::Error;
using u3d::nn::ConfigReader;

TEST(ConfigReader, IntegralFloatsAreIntsAndOutOfRangeFloatsAreErrors) {
  nlohmann::json json = nlohmann::json::parse(
      R"({"one": 1.0, "neg": -4.0, "half": 2.5, "huge": 1e300, "edge": 9223372036854775808.0, "low": -9223372036854775808.0})");
  ConfigReader r(json, "config.json");
  EXPECT_EQ(r.get_int("one", 0), 1);
  EXPECT_EQ(r.get_int("neg", 0), -4);
  EXPECT_EQ(r.get_int("low", 0), INT64_MIN);
  EXPECT_EQ(r.get_int("absent", 7), 7);
  for (const char* key : {"half", "huge", "edge"}) {
    try {
      r.get_int(key, 0);
      ADD_FAILURE() << key << " was accepted as an integer";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("'") + key + "' must be an integer"), std::string::npos) << e.what();
    }
  }
}
