// Parameter conventions shared by every options struct of the library.
//
// Each options struct holds its defaults in field initializers (written once), has a
// validate() that throws std::invalid_argument naming "Struct.field = value: rule", and lists
// its fields once in visit(), which the ini loader (MRPT bridge), the config dump and the docs
// use. SI units and radians inside; ini keys ending in _deg are converted by angleDeg().
//
// A visitor implements:
//   void operator()(const char* key, double& v, const char* doc);
//   void operator()(const char* key, int& v, const char* doc);
//   void operator()(const char* key, bool& v, const char* doc);
//   void operator()(const char* key, Eigen::Vector3f& v, const char* doc);
//   void angleDeg(const char* key, double& radians, const char* doc);
//   template <class E, std::size_t N>
//   void choice(const char* key, E& value, const EnumName<E> (&names)[N], const char* doc);
// An enum field is visited through choice() with the table of its ini names (enumNames() of
// the enum, defined beside it); the loader also accepts the enum's number, as configs written
// before the names were introduced hold it.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <sstream>
#include <stdexcept>
#include <string>

namespace upd::core {

namespace detail {
template <class T>
std::string formatValue(const T& v) {
  std::ostringstream os;
  os << v;
  return os.str();
}
inline std::string formatValue(const Eigen::Vector3f& v) {
  std::ostringstream os;
  os << v.x() << "," << v.y() << "," << v.z();
  return os.str();
}
}  // namespace detail

/// Throws std::invalid_argument("<owner>.<field> = <value>: <rule>") unless ok.
template <class T>
void requireParam(bool ok, const char* owner, const char* field, const T& value, const char* rule) {
  if (!ok) {
    throw std::invalid_argument(std::string(owner) + "." + field + " = " +
                                detail::formatValue(value) + ": " + rule);
  }
}

/// One ini name of an enum value.
template <class E>
struct EnumName {
  const char* name;
  E value;
};

/// The name of value in names, or nullptr when the table lacks it.
template <class E, std::size_t N>
const char* enumName(const EnumName<E> (&names)[N], E value) {
  for (const auto& n : names) {
    if (n.value == value) return n.name;
  }
  return nullptr;
}

/// "a|b|c": the names of a table, for messages and docs.
template <class E, std::size_t N>
std::string enumNameList(const EnumName<E> (&names)[N]) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : "|") + std::string(n.name);
  return out;
}

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

}  // namespace upd::core
