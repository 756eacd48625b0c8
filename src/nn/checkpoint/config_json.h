#pragma once
// Reading model configs (diffusers / transformers config.json) with errors that name the file and key.
// A key that is absent or JSON null takes the library's default, as the Python constructors do.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace u3d::nn {

// Parses a JSON file; Error naming the file if it is missing or not valid JSON.
nlohmann::json read_json_file(const std::filesystem::path& path);

class ConfigReader {
 public:
  // `source` names the config in error messages (usually its path).
  ConfigReader(const nlohmann::json& json, std::string source);

  bool has(const std::string& key) const;  // present and not null
  int64_t get_int(const std::string& key, int64_t fallback) const;
  double get_double(const std::string& key, double fallback) const;
  bool get_bool(const std::string& key, bool fallback) const;
  std::string get_string(const std::string& key, const std::string& fallback) const;
  std::vector<int64_t> get_int_list(const std::string& key) const;  // required
  std::vector<double> get_double_list(const std::string& key, const std::vector<double>& fallback) const;
  std::vector<std::string> get_string_list(const std::string& key) const;  // required
  // An int applies to every one of `count` entries; a list must have exactly `count` entries.
  std::vector<int64_t> get_int_or_list(const std::string& key, int64_t fallback, size_t count) const;

  // Error "<source>: <key> = <value>: <why>" for settings this implementation does not support.
  [[noreturn]] void unsupported(const std::string& key, const std::string& why) const;
  // Calls unsupported() unless the key is absent/null or equals `expected`.
  void require_value(const std::string& key, const nlohmann::json& expected) const;

  const std::string& source() const { return source_; }

 private:
  const nlohmann::json& value(const std::string& key) const;
  [[noreturn]] void bad_type(const std::string& key, const char* expected) const;

  const nlohmann::json& json_;
  std::string source_;
};

}  // namespace u3d::nn
