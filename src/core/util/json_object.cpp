#include "binloop/util/json_object.h"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace binloop {

std::string JsonObject::quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char hex[8];
          std::snprintf(hex, sizeof hex, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
          out += hex;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

JsonObject& JsonObject::add(const std::string& key, const std::string& value) {
  return addRaw(key, quoted(value));
}

JsonObject& JsonObject::add(const std::string& key, double value) {
  if (!std::isfinite(value)) return addRaw(key, "null");  // JSON has no NaN or infinity
  std::ostringstream s;
  s.precision(6);
  s << value;
  return addRaw(key, s.str());
}

JsonObject& JsonObject::addRaw(const std::string& key, const std::string& json) {
  fields_.emplace_back(key, json);
  return *this;
}

std::string JsonObject::str(int depth) const {
  const bool lines = depth == 0 || multiline_;
  const std::string pad(2 * static_cast<size_t>(depth + 1), ' '),
      close_pad(2 * static_cast<size_t>(depth), ' ');
  std::string out = "{";
  for (size_t i = 0; i < fields_.size(); ++i) {
    out += i ? (lines ? ",\n" : ", ") : (lines ? "\n" : "");
    if (lines) out += pad;
    out += quoted(fields_[i].first) + ": " + fields_[i].second;
  }
  if (lines && !fields_.empty()) out += "\n" + close_pad;
  out += "}";
  return depth == 0 ? out + "\n" : out;
}

}  // namespace binloop
