#include "nn/checkpoint/config_json.h"

#include <cmath>
#include <fstream>

#include "core/error.h"

namespace u3d::nn {

nlohmann::json read_json_file(const std::filesystem::path& path) {
  std::ifstream is(path);
  if (!is) throw Error("cannot open " + path.string());
  try {
    return nlohmann::json::parse(is);
  } catch (const nlohmann::json::exception& e) {
    throw Error(path.string() + " is not valid JSON: " + e.what());
  }
}

ConfigReader::ConfigReader(const nlohmann::json& json, std::string source) : json_(json), source_(std::move(source)) {
  if (!json_.is_object()) throw Error(source_ + ": config is not a JSON object");
}

bool ConfigReader::has(const std::string& key) const { return json_.contains(key) && !json_.at(key).is_null(); }

const nlohmann::json& ConfigReader::value(const std::string& key) const { return json_.at(key); }

void ConfigReader::bad_type(const std::string& key, const char* expected) const {
  throw Error(source_ + ": '" + key + "' must be " + expected + ", got " + (has(key) ? value(key).dump() : "nothing"));
}

int64_t ConfigReader::get_int(const std::string& key, int64_t fallback) const {
  if (!has(key)) return fallback;
  const auto& v = value(key);
  if (v.is_number_integer()) return v.get<int64_t>();
  // Python configs sometimes store integral values as floats (e.g. 1.0). Casting a double outside the
  // int64 range is undefined, so the range is checked first ([-2^63, 2^63)).
  if (v.is_number_float()) {
    const double d = v.get<double>();
    if (d >= -9223372036854775808.0 && d < 9223372036854775808.0 && d == std::trunc(d)) return static_cast<int64_t>(d);
  }
  bad_type(key, "an integer");
}

double ConfigReader::get_double(const std::string& key, double fallback) const {
  if (!has(key)) return fallback;
  if (!value(key).is_number()) bad_type(key, "a number");
  return value(key).get<double>();
}

bool ConfigReader::get_bool(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  if (!value(key).is_boolean()) bad_type(key, "true or false");
  return value(key).get<bool>();
}

std::string ConfigReader::get_string(const std::string& key, const std::string& fallback) const {
  if (!has(key)) return fallback;
  if (!value(key).is_string()) bad_type(key, "a string");
  return value(key).get<std::string>();
}

std::vector<int64_t> ConfigReader::get_int_list(const std::string& key) const {
  if (!has(key) || !value(key).is_array()) bad_type(key, "a list of integers");
  std::vector<int64_t> out;
  for (const auto& v : value(key)) {
    if (!v.is_number_integer()) bad_type(key, "a list of integers");
    out.push_back(v.get<int64_t>());
  }
  return out;
}

std::vector<double> ConfigReader::get_double_list(const std::string& key, const std::vector<double>& fallback) const {
  if (!has(key)) return fallback;
  if (!value(key).is_array()) bad_type(key, "a list of numbers");
  std::vector<double> out;
  for (const auto& v : value(key)) {
    if (!v.is_number()) bad_type(key, "a list of numbers");
    out.push_back(v.get<double>());
  }
  return out;
}

std::vector<std::string> ConfigReader::get_string_list(const std::string& key) const {
  if (!has(key) || !value(key).is_array()) bad_type(key, "a list of strings");
  std::vector<std::string> out;
  for (const auto& v : value(key)) {
    if (!v.is_string()) bad_type(key, "a list of strings");
    out.push_back(v.get<std::string>());
  }
  return out;
}

std::vector<int64_t> ConfigReader::get_int_or_list(const std::string& key, int64_t fallback, size_t count) const {
  if (!has(key) || value(key).is_number()) return std::vector<int64_t>(count, get_int(key, fallback));
  std::vector<int64_t> out = get_int_list(key);
  if (out.size() != count)
    throw Error(source_ + ": '" + key + "' has " + std::to_string(out.size()) + " entries, expected " + std::to_string(count));
  return out;
}

void ConfigReader::unsupported(const std::string& key, const std::string& why) const {
  throw Error(source_ + ": " + key + " = " + (json_.contains(key) ? value(key).dump() : "(absent)") +
              " is not supported: " + why);
}

void ConfigReader::require_value(const std::string& key, const nlohmann::json& expected) const {
  if (!has(key)) return;
  const auto& v = value(key);
  // 1 and 1.0 are the same setting.
  if (v == expected || (v.is_number() && expected.is_number() && v.get<double>() == expected.get<double>())) return;
  unsupported(key, "only " + expected.dump() + " is implemented");
}

}  // namespace u3d::nn
