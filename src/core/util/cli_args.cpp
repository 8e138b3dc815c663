#include "binloop/util/cli_args.h"

#include <cerrno>
#include <cstdlib>
#include <iostream>
#include <sstream>

namespace binloop {

CliArgs::CliArgs(std::string tool, std::string usage) : tool_(std::move(tool)), usage_(std::move(usage)) {}

CliArgs& CliArgs::option(const std::string& name, const std::string& help, const std::string& def) {
  // Two declarations of one name (a tool's own option and a shared set's) would silently merge.
  if (!opts_.emplace(name, Opt{help, def, false}).second)
    throw std::logic_error(tool_ + ": option --" + name + " declared twice");
  return *this;
}

CliArgs& CliArgs::flag(const std::string& name, const std::string& help) {
  if (!opts_.emplace(name, Opt{help, "", true}).second)
    throw std::logic_error(tool_ + ": option --" + name + " declared twice");
  return *this;
}

CliArgs& CliArgs::positional(const std::string& name, const std::string& help) {
  positionals_.emplace_back(name, help);
  return *this;
}

bool CliArgs::parse(int argc, char** argv) {
  size_t next_pos = 0;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::cout << usage();
      return false;
    }
    if (a.rfind("--", 0) == 0) {
      std::string name = a.substr(2), value;
      bool inline_value = false;
      if (const auto eq = name.find('='); eq != std::string::npos) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
        inline_value = true;
      }
      auto it = opts_.find(name);
      if (it == opts_.end()) throw CliError("unknown option --" + name + " (see " + tool_ + " --help)");
      if (it->second.is_flag) {
        if (inline_value) throw CliError("--" + name + " takes no value");
        values_.emplace(name, "1");
        continue;
      }
      if (!inline_value) {
        if (i + 1 >= argc) throw CliError("--" + name + " needs a value");
        value = argv[++i];
      }
      values_.emplace(name, value);
    } else {
      if (next_pos >= positionals_.size()) throw CliError("unexpected argument '" + a + "'");
      values_.emplace(positionals_[next_pos++].first, a);
    }
  }
  if (next_pos < positionals_.size())
    throw CliError("missing argument <" + positionals_[next_pos].first + "> (see " + tool_ + " --help)");
  return true;
}

bool CliArgs::has(const std::string& name) const { return values_.count(name) > 0; }

std::string CliArgs::str(const std::string& name) const {
  auto range = values_.equal_range(name);
  if (range.first != range.second) return std::prev(range.second)->second;  // last one wins
  auto it = opts_.find(name);
  return it == opts_.end() ? "" : it->second.def;
}

std::vector<std::string> CliArgs::all(const std::string& name) const {
  std::vector<std::string> out;
  auto range = values_.equal_range(name);
  for (auto it = range.first; it != range.second; ++it) out.push_back(it->second);
  return out;
}

long CliArgs::integer(const std::string& name) const {
  const std::string s = str(name);
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0' || errno)
    throw CliError("--" + name + " must be a whole number, got '" + s + "'");
  return v;
}

double CliArgs::number(const std::string& name) const {
  const std::string s = str(name);
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0' || errno) throw CliError("--" + name + " must be a number, got '" + s + "'");
  return v;
}

std::string CliArgs::usage() const {
  std::ostringstream s;
  s << "usage: " << usage_ << "\n";
  for (const auto& [n, h] : positionals_) s << "  <" << n << ">  " << h << "\n";
  for (const auto& [n, o] : opts_) {
    s << "  --" << n << (o.is_flag ? "" : " <v>") << "  " << o.help;
    if (!o.def.empty()) s << " (default " << o.def << ")";
    s << "\n";
  }
  return s.str();
}

int runTool(const std::string& tool, const std::function<int()>& body) {
  try {
    return body();
  } catch (const CliError& e) {
    std::cerr << tool << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << tool << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace binloop
