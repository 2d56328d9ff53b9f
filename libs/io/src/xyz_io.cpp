// XYZ text: the lowest common denominator every tool can export (CloudCompare, MeshLab, scripts).
#include "upd/io/atomic_file.h"
#include "upd/io/cloud_io.h"

#include "io_detail.h"

#include <charconv>
#include <fstream>
#include <ostream>
#include <vector>

namespace upd::io {

namespace {

using detail::fileError;

bool isSeparator(char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r'; }

/// Splits a line at whitespace/commas, dropping a `#` comment. Tokens point into line.
void tokenize(const std::string& line, std::vector<std::pair<const char*, const char*>>& tokens) {
  tokens.clear();
  const char* p = line.data();
  const char* end = p + line.size();
  while (p != end) {
    if (*p == '#') break;
    if (isSeparator(*p)) {
      ++p;
      continue;
    }
    const char* start = p;
    while (p != end && !isSeparator(*p) && *p != '#') ++p;
    tokens.emplace_back(start, p);
  }
}

bool parseDouble(const char* first, const char* last, double& v) {
  if (first != last && *first == '+') ++first;  // from_chars rejects a leading '+'
  const auto r = std::from_chars(first, last, v);
  return r.ec == std::errc() && r.ptr == last;
}

}  // namespace

core::PointCloud readXyz(const std::string& path) {
  detail::requireReadableFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw fileError(path, "cannot open for reading");

  core::PointCloud cloud;
  std::vector<std::pair<const char*, const char*>> tokens;
  std::string line;
  std::size_t line_no = 0;
  std::size_t columns = 0;  // fixed by the first point line: 3 or 6
  bool seen_content = false;
  double v[6];
  while (std::getline(in, line)) {
    ++line_no;
    tokenize(line, tokens);
    if (tokens.empty()) continue;
    const std::string where = "line " + std::to_string(line_no) + ": ";
    bool no_number = true;
    std::string bad_token;
    for (std::size_t k = 0; k < tokens.size(); ++k) {
      double d;
      const bool ok = parseDouble(tokens[k].first, tokens[k].second, d);
      if (!ok && bad_token.empty()) bad_token.assign(tokens[k].first, tokens[k].second);
      no_number = no_number && !ok;
      if (ok && k < 6) v[k] = d;
    }
    if (!seen_content) {
      seen_content = true;
      if (no_number) continue;  // a column header line such as "x,y,z"
    }
    if (!bad_token.empty()) {
      if (bad_token.size() > 40) bad_token = bad_token.substr(0, 40) + "...";
      throw fileError(path, where + "'" + bad_token + "' is not a number");
    }
    if (columns == 0) {
      if (tokens.size() != 3 && tokens.size() != 6) {
        throw fileError(path, where + "expected 'x y z' or 'x y z r g b', got " +
                                  std::to_string(tokens.size()) + " values");
      }
      columns = tokens.size();
    } else if (tokens.size() != columns) {
      throw fileError(path, where + "expected " + std::to_string(columns) + " values like the " +
                                "first point line, got " + std::to_string(tokens.size()));
    }
    if (columns == 6) {
      for (int k = 3; k < 6; ++k) {
        if (!(v[k] >= 0.0 && v[k] <= 255.0)) {
          throw fileError(path, where + "colour value out of 0..255");
        }
      }
      cloud.push_back(static_cast<float>(v[0]), static_cast<float>(v[1]),
                      static_cast<float>(v[2]), static_cast<std::uint8_t>(v[3] + 0.5),
                      static_cast<std::uint8_t>(v[4] + 0.5), static_cast<std::uint8_t>(v[5] + 0.5));
    } else {
      cloud.push_back(static_cast<float>(v[0]), static_cast<float>(v[1]),
                      static_cast<float>(v[2]));
    }
  }
  if (in.bad()) throw fileError(path, "read error after line " + std::to_string(line_no));
  return cloud;
}

void writeXyz(const std::string& path, const core::PointCloud& cloud) {
  const std::size_t n = cloud.size();
  if (cloud.y.size() != n || cloud.z.size() != n) {
    throw std::invalid_argument("writeXyz: x, y, z of the cloud differ in size");
  }
  const bool color = cloud.hasColor();
  writeFileAtomically(path, [&](std::ostream& os) {
    std::string buf;
    char num[64];
    auto put = [&](float f) {
      // Shortest text that reads back to the same float; NaN becomes "nan", which readXyz reads.
      const auto r = std::to_chars(num, num + sizeof num, f);
      buf.append(num, r.ptr);
    };
    for (std::size_t i = 0; i < n; ++i) {
      put(cloud.x[i]);
      buf += ' ';
      put(cloud.y[i]);
      buf += ' ';
      put(cloud.z[i]);
      if (color) {
        buf += ' ' + std::to_string(cloud.r[i]) + ' ' + std::to_string(cloud.g[i]) + ' ' +
               std::to_string(cloud.b[i]);
      }
      buf += '\n';
      if (buf.size() > (1u << 20)) {
        os.write(buf.data(), static_cast<std::streamsize>(buf.size()));
        buf.clear();
      }
    }
    os.write(buf.data(), static_cast<std::streamsize>(buf.size()));
  });
}

}  // namespace upd::io
