#pragma once
// The one JSON writer of the tools and benchmarks (summary.json, the benches' .json files): an object of
// fields in the order they were added, strings escaped, numbers as a stream writes them with 6 significant
// digits. Top-level objects go one field a line; nested ones on one line unless made with `multiline`.
// binloop/io/json_fields.h reads them back (eval-slam).
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace binloop {

class JsonObject {
 public:
  explicit JsonObject(bool multiline = false) : multiline_(multiline) {}

  JsonObject& add(const std::string& key, const std::string& value);
  JsonObject& add(const std::string& key, const char* value) { return add(key, std::string(value)); }
  JsonObject& add(const std::string& key, double value);
  JsonObject& add(const std::string& key, int value) { return addInteger(key, value); }
  JsonObject& add(const std::string& key, long value) { return addInteger(key, value); }
  JsonObject& add(const std::string& key, long long value) { return addInteger(key, value); }
  JsonObject& add(const std::string& key, unsigned value) { return addUnsigned(key, value); }
  JsonObject& add(const std::string& key, unsigned long value) { return addUnsigned(key, value); }
  JsonObject& add(const std::string& key, unsigned long long value) { return addUnsigned(key, value); }
  JsonObject& add(const std::string& key, bool value) { return addRaw(key, value ? "true" : "false"); }
  JsonObject& add(const std::string& key, const JsonObject& value) { return addRaw(key, value.str(1)); }
  /// A value that is JSON already (a number as another tool printed it).
  JsonObject& addRaw(const std::string& key, const std::string& json);

  bool empty() const { return fields_.empty(); }
  /// The object; `depth` 0 ends with a newline (a file), deeper ones are indented to sit in their parent.
  std::string str(int depth = 0) const;

  static std::string quoted(const std::string& text);

 private:
  JsonObject& addInteger(const std::string& key, long long value) {
    return addRaw(key, std::to_string(value));
  }
  JsonObject& addUnsigned(const std::string& key, unsigned long long value) {
    return addRaw(key, std::to_string(value));
  }

  bool multiline_;
  std::vector<std::pair<std::string, std::string>> fields_;  // key, JSON value
};

}  // namespace binloop
