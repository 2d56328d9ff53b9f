#include "cli.h"

#include <sstream>

namespace upd::app {

Args::Args(const std::vector<std::string>& argv, const std::set<std::string>& options,
           const std::set<std::string>& flags) {
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a.size() > 2 && a.rfind("--", 0) == 0) {
      std::string name = a, value;
      const auto eq = a.find('=');
      const bool inline_value = eq != std::string::npos;
      if (inline_value) {
        name = a.substr(0, eq);
        value = a.substr(eq + 1);
      }
      if (flags.count(name)) {
        if (inline_value) throw UsageError("option " + name + " takes no value");
        flags_.insert(name);
      } else if (options.count(name)) {
        if (!inline_value) {
          if (i + 1 >= argv.size()) throw UsageError("option " + name + " needs a value");
          value = argv[++i];
        }
        values_[name] = value;
      } else {
        throw UsageError("unknown option " + name);
      }
    } else {
      positionals_.push_back(a);
    }
  }
}

std::optional<std::string> Args::str(const std::string& name) const {
  const auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::optional<double> Args::number(const std::string& name) const {
  const auto v = str(name);
  if (!v) return std::nullopt;
  try {
    std::size_t used = 0;
    const double d = std::stod(*v, &used);
    if (used == v->size()) return d;
  } catch (const std::exception&) {
  }
  throw UsageError("option " + name + " = '" + *v + "': not a number");
}

std::optional<int> Args::integer(const std::string& name) const {
  const auto v = str(name);
  if (!v) return std::nullopt;
  try {
    std::size_t used = 0;
    const int i = std::stoi(*v, &used);
    if (used == v->size()) return i;
  } catch (const std::exception&) {
  }
  throw UsageError("option " + name + " = '" + *v + "': not an integer");
}

std::optional<Eigen::Vector3f> Args::vector3(const std::string& name) const {
  const auto v = str(name);
  if (!v) return std::nullopt;
  std::string t = *v;
  for (char& c : t) c = c == ',' ? ' ' : c;
  std::istringstream is(t);
  Eigen::Vector3f out;
  std::string extra;
  if (!(is >> out.x() >> out.y() >> out.z()) || (is >> extra) || !out.allFinite()) {
    throw UsageError("option " + name + " = '" + *v + "': expected three numbers X,Y,Z");
  }
  return out;
}

}  // namespace upd::app
