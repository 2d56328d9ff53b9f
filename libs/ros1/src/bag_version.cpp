#include "bag_version.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>

#include "bag_walk.h"

namespace upd::ros1::detail {

namespace {

// sscanf's %d at p, read as strtoll reads it (white space, a sign, digits: the same grammar,
// but defined past an int's range, where %d is not): its text without the white space, and its
// value where that fits an int (rosbag's version arithmetic overflows beyond). p moves past it;
// false, p left, without a digit.
bool readIntField(const char*& p, std::string& text, std::optional<long long>& value) {
  while (std::isspace(static_cast<unsigned char>(*p))) ++p;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(p, &end, 10);
  if (end == p) return false;
  const bool fits = errno != ERANGE && v >= std::numeric_limits<int>::min() &&
                    v <= std::numeric_limits<int>::max();
  text.assign(p, static_cast<std::size_t>(end - p));
  value = fits ? std::optional<long long>(v) : std::nullopt;
  p = end;
  return true;
}

}  // namespace

VersionLine bagVersion(std::ifstream& in, std::uint64_t& after) {
  std::string line(1023, '\0');
  in.seekg(0);
  in.read(line.data(), static_cast<std::streamsize>(line.size()));
  line.resize(static_cast<std::size_t>(in.gcount()));
  in.clear();
  const auto newline = line.find('\n');
  after = newline == std::string::npos ? line.size() : newline + 1;
  line.resize(std::min<std::size_t>(after, line.find('\0')));  // as sscanf sees it
  VersionLine v;
  if (line.rfind("#ROS", 0) != 0) return v;
  // rosbag's unbounded %s writes a longer word past its 100-byte buffer.
  const auto word_end = line.find_first_of(" \t\n\v\f\r", 4);
  if ((word_end == std::string::npos ? line.size() : word_end) - 4 >= 100) {
    throw BagDamage("the version line's word after '#ROS' has 100 or more characters");
  }
  char word[100];
  int end_of_word = 0;
  if (std::sscanf(line.c_str(), "#ROS%99s%n", word, &end_of_word) != 1) return v;
  const char* p = line.c_str() + end_of_word;
  while (std::isspace(static_cast<unsigned char>(*p))) ++p;  // the format's " V"
  if (*p++ != 'V') return v;
  std::string major, minor;
  std::optional<long long> ma, mi;
  if (!readIntField(p, major, ma) || *p++ != '.' || !readIntField(p, minor, mi)) return v;
  v.found = true;
  v.text = major + "." + minor;
  v.is_2_0 = ma && mi && *ma * 100 + *mi == 200;
  return v;
}

}  // namespace upd::ros1::detail
