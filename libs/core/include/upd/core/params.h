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
#pragma once

#include <Eigen/Core>

#include <sstream>
#include <stdexcept>
#include <string>

namespace upd {

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

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

}  // namespace upd
