// What a call throws, as text: the tests of one-line error messages compare it.
#pragma once

#include <exception>
#include <functional>
#include <string>

namespace upd::test {

/// The what() of the std::exception f throws, or "" when it returns.
inline std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace upd::test
