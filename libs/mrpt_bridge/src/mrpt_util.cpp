#include "mrpt_util.h"

#include <mrpt/system/datetime.h>

#include <limits>
#include <sstream>

namespace upd::mrpt_bridge::detail {

std::string shortClassName(const mrpt::rtti::CObject& object) {
  std::string name = object.GetRuntimeClass()->className;
  const auto pos = name.rfind("::");
  return pos == std::string::npos ? name : name.substr(pos + 2);
}

double toSeconds(const mrpt::Clock::time_point& t) {
  if (t == INVALID_TIMESTAMP) return std::numeric_limits<double>::quiet_NaN();
  return mrpt::Clock::toDouble(t);
}

std::string condenseMessage(const std::string& what) {
  const auto strip = [](std::string s) {
    s.erase(0, s.find_first_not_of(" \t"));
    s.erase(s.find_last_not_of(" \t\r") + 1);
    return s;
  };
  std::istringstream is(what);
  std::string line, messages, others;
  while (std::getline(is, line)) {
    line = strip(line);
    if (line.empty() || line.rfind("====", 0) == 0 || line.rfind("Call stack", 0) == 0 ||
        line.rfind("[", 0) == 0) {
      continue;  // banner and backtrace
    }
    if (line.rfind("Message:", 0) == 0) {
      const std::string m = strip(line.substr(8));
      if (!m.empty()) messages += (messages.empty() ? "" : ": ") + m;
    } else {
      // "Location: ..." sometimes holds the only text (e.g. a std::filesystem error).
      const std::string o = line.rfind("Location:", 0) == 0 ? strip(line.substr(9)) : line;
      if (!o.empty()) others += (others.empty() ? "" : ": ") + o;
    }
  }
  std::string out = !messages.empty() ? messages : !others.empty() ? others : what;
  for (char& c : out) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u >= 0x7f) c = '?';
  }
  return out;
}

}  // namespace upd::mrpt_bridge::detail
