// A small command-line parser for the `upd` subcommands: positionals, `--key value` options
// and flags, with strict checks (an unknown option or a malformed number is an error that
// names the option and the value).
#pragma once

#include <Eigen/Core>

#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace upd::app {

/// A mistake in the command line: main prints it with the usage hint and exits with 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Args {
 public:
  /// options: names taking a value ("--radius-m"); flags: names without ("--no-preprocess").
  Args(const std::vector<std::string>& argv, const std::set<std::string>& options,
       const std::set<std::string>& flags);

  const std::vector<std::string>& positionals() const { return positionals_; }
  bool flag(const std::string& name) const { return flags_.count(name) > 0; }
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  std::optional<std::string> str(const std::string& name) const;
  std::optional<double> number(const std::string& name) const;
  std::optional<int> integer(const std::string& name) const;
  std::optional<Eigen::Vector3f> vector3(const std::string& name) const;

 private:
  std::vector<std::string> positionals_;
  std::map<std::string, std::string> values_;
  std::set<std::string> flags_;
};

}  // namespace upd::app
