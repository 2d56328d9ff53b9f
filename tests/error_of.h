// What a call throws, as text: the tests of one-line error messages compare it.
#pragma once

#include <exception>
#include <functional>
#include <string>

namespace upd::test {

/// The what() of the exception of type E (or derived) that f throws, or "" when it returns.
/// Another type escapes, and fails the test: name E where the test holds the type too.
template <class E = std::exception>
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

}  // namespace upd::test
