#include "binloop/io/json_fields.h"

#include <cmath>
#include <cstdlib>

#include "binloop/io/data_error.h"

namespace binloop {

namespace {

class Reader {
 public:
  Reader(const std::string& text, const std::string& source) : s_(text), source_(source) {}

  JsonFields object() {
    JsonFields out;
    expect('{');
    if (peek() == '}') return ++i_, end(std::move(out));
    for (;;) {
      if (peek() != '"') fail("a field name in quotes");
      std::string key = string();
      expect(':');
      std::string value = peek() == '"' ? string() : raw();
      if (!out.emplace(std::move(key), std::move(value)).second) fail("no repeated field name");
      if (peek() == ',') {
        ++i_;
        continue;
      }
      expect('}');
      return end(std::move(out));
    }
  }

 private:
  JsonFields end(JsonFields out) {
    if (peek() != '\0') fail("nothing after the object");
    return out;
  }

  // The next character after white space, '\0' at the end.
  char peek() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\n' || s_[i_] == '\t' || s_[i_] == '\r')) ++i_;
    return i_ < s_.size() ? s_[i_] : '\0';
  }

  void expect(char c) {
    if (peek() != c) fail(std::string("'") + c + "'");
    ++i_;
  }

  [[noreturn]] void fail(const std::string& wanted) const {
    throw DataError(source_ + ": not the JSON object expected: " + wanted + " wanted at offset " +
                    std::to_string(i_));
  }

  std::string string() {
    ++i_;  // the opening quote
    std::string out;
    while (i_ < s_.size() && s_[i_] != '"') {
      char c = s_[i_++];
      if (c == '\\') {
        if (i_ >= s_.size()) break;
        c = s_[i_++];
        if (c == 'u') {
          if (i_ + 4 > s_.size()) fail("four hex digits after \\u");
          const long code = std::strtol(s_.substr(i_, 4).c_str(), nullptr, 16);
          i_ += 4;
          utf8(code, &out);
          continue;
        }
        c = unescaped(c);
      }
      out += c;
    }
    if (i_ >= s_.size()) fail("a closing quote");
    ++i_;
    return out;
  }

  // '"', '\\' and '/' stand for themselves.
  static char unescaped(char c) {
    static const std::string from = "ntrbf", to = "\n\t\r\b\f";
    const std::size_t at = from.find(c);
    return at == std::string::npos ? c : to[at];
  }

  static void utf8(long code, std::string* out) {
    if (code < 0x80) {
      *out += static_cast<char>(code);
    } else if (code < 0x800) {
      *out += static_cast<char>(0xc0 | (code >> 6));
      *out += static_cast<char>(0x80 | (code & 0x3f));
    } else {
      *out += static_cast<char>(0xe0 | (code >> 12));
      *out += static_cast<char>(0x80 | ((code >> 6) & 0x3f));
      *out += static_cast<char>(0x80 | (code & 0x3f));
    }
  }

  // A value other than a string, as written: a literal up to the next ',' or '}', or a nested object or
  // array up to its matching bracket (strings inside it skipped whole).
  std::string raw() {
    const size_t from = i_;
    if (i_ >= s_.size()) fail("a value");
    if (s_[i_] == '{' || s_[i_] == '[') {
      int depth = 0;
      do {
        const char c = s_[i_];
        if (c == '"') {
          string();
          continue;
        }
        depth += (c == '{' || c == '[') - (c == '}' || c == ']');
        ++i_;
      } while (depth > 0 && i_ < s_.size());
      if (depth > 0) fail("a closing bracket");
    } else {
      while (i_ < s_.size() && s_[i_] != ',' && s_[i_] != '}' && s_[i_] != '\n' && s_[i_] != ' ') ++i_;
      if (i_ == from) fail("a value");
    }
    return s_.substr(from, i_ - from);
  }

  const std::string& s_;
  const std::string& source_;
  size_t i_ = 0;
};

}  // namespace

JsonFields readJsonFields(const std::string& text, const std::string& source) {
  return Reader(text, source).object();
}

double jsonNumber(const JsonFields& fields, const std::string& key) {
  const auto it = fields.find(key);
  if (it == fields.end() || it->second.empty()) return NAN;
  char* end = nullptr;
  const double d = std::strtod(it->second.c_str(), &end);
  return *end ? NAN : d;
}

}  // namespace binloop
