#pragma once
// The command-line parser every tool uses, so that all of them treat options alike: `--name value`,
// `--name=value`, boolean `--flag`, positionals in order, `--help`. Unknown options, missing values and
// non-numeric numbers throw CliError with a message naming the option.
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace binloop {

class CliError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class CliArgs {
 public:
  /// `usage` is printed by usage(); options are declared before parse().
  CliArgs(std::string tool, std::string usage);
  CliArgs& option(const std::string& name, const std::string& help, const std::string& default_value = "");
  CliArgs& flag(const std::string& name, const std::string& help);
  CliArgs& positional(const std::string& name, const std::string& help);
  /// Returns false when --help was asked for (usage() has then been printed to stdout).
  bool parse(int argc, char** argv);

  std::string str(const std::string& name) const;
  bool has(const std::string& name) const;  // given on the command line (or a flag that is set)
  long integer(const std::string& name) const;
  double number(const std::string& name) const;
  /// All values of an option that may be repeated (e.g. --images a --images b).
  std::vector<std::string> all(const std::string& name) const;
  std::string usage() const;

 private:
  struct Opt {
    std::string help, def;
    bool is_flag = false;
  };
  std::string tool_, usage_;
  std::map<std::string, Opt> opts_;
  std::vector<std::pair<std::string, std::string>> positionals_;
  std::multimap<std::string, std::string> values_;
};

/// Runs a tool's body with the exit-code convention every tool shares: 0 done, 2 bad command line
/// (CliError, message prefixed with the tool's name), 1 any other error ("<tool>: error: ...").
int runTool(const std::string& tool, const std::function<int()>& body);

}  // namespace binloop
