// Command-line numbers of the benchmark programs: a bad one is a std::invalid_argument that
// names the option and the text (std::stoi's own says only "stoi").
#pragma once

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace upd::bench {

/// text as a finite number, or std::invalid_argument "what: not a number".
inline double number(const std::string& what, const std::string& text) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v)) {
    throw std::invalid_argument(what + ": not a number");
  }
  return v;
}

/// The value of option as a whole number >= 1 (at most 1,000,000).
inline int positiveCount(const std::string& option, const std::string& text) {
  const double v = number(option + " " + text, text);
  if (v < 1 || v > 1e6 || v != std::floor(v)) {
    throw std::invalid_argument(option + " " + text + ": must be a whole number from 1 to 1000000");
  }
  return static_cast<int>(v);
}

}  // namespace upd::bench
