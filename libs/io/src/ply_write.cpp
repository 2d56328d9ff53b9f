// PLY: the project's one PLY writer (binary little-endian, any float or uchar columns), used by
// writePly and the scored PLY. Written through a temporary file, so a failed write leaves none.
#include "upd/io/atomic_file.h"
#include "upd/io/cloud_io.h"
#include "upd/core/version.h"

#include "io_detail.h"
#include "ply_detail.h"

#include <algorithm>
#include <cmath>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace upd::io {

namespace detail {

void writeBinaryPly(const std::string& path, std::size_t n, const std::vector<PlyColumn>& columns,
                    const std::vector<std::string>& comments, bool drop_non_finite_xyz) {
  if (drop_non_finite_xyz &&
      (columns.size() < 3 || columns[0].name != "x" || columns[1].name != "y" ||
       columns[2].name != "z" ||
       (n > 0 && (!columns[0].f || !columns[1].f || !columns[2].f)))) {
    throw std::invalid_argument("writeBinaryPly: drop_non_finite_xyz needs x, y, z first");
  }
  auto keep = [&](std::size_t i) {
    return !drop_non_finite_xyz || (std::isfinite(columns[0].f[i]) &&
                                    std::isfinite(columns[1].f[i]) &&
                                    std::isfinite(columns[2].f[i]));
  };
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i) kept += keep(i) ? 1 : 0;

  std::string header = "ply\nformat binary_little_endian 1.0\ncomment UPD-Nav " +
                       std::string(core::version()) + "\n";
  for (std::string c : comments) {
    std::replace(c.begin(), c.end(), '\n', ' ');
    std::replace(c.begin(), c.end(), '\r', ' ');
    header += "comment " + c + "\n";
  }
  header += "element vertex " + std::to_string(kept) + "\n";
  std::size_t stride = 0;
  for (const PlyColumn& c : columns) {
    header += std::string("property ") + (c.is_uchar ? "uchar " : "float ") + c.name + "\n";
    stride += c.is_uchar ? 1 : 4;
  }
  header += "end_header\n";

  writeFileAtomically(path, [&](std::ostream& os) {
    os.write(header.data(), static_cast<std::streamsize>(header.size()));
    // Encode in chunks: bounded memory however big the cloud, few large writes.
    constexpr std::size_t kChunk = 1 << 16;
    std::string buf;
    buf.reserve(kChunk * stride);
    for (std::size_t first = 0; first < n; first += kChunk) {
      buf.clear();
      const std::size_t last = std::min(n, first + kChunk);
      for (std::size_t i = first; i < last; ++i) {
        if (!keep(i)) continue;
        for (const PlyColumn& c : columns) {
          if (c.is_uchar) {
            buf.push_back(static_cast<char>(c.u8 ? c.u8[i] : c.fill_u8));
          } else {
            appendLittleEndian(buf, c.f ? c.f[i] : c.fill_f);
          }
        }
      }
      os.write(buf.data(), static_cast<std::streamsize>(buf.size()));
    }
  });
}

}  // namespace detail

void writePly(const std::string& path, const core::PointCloud& cloud, const std::vector<core::Label>* labels,
              const PlyWriteOptions& options) {
  const std::size_t n = cloud.size();
  if (cloud.y.size() != n || cloud.z.size() != n) {
    throw std::invalid_argument("writePly: x, y, z of the cloud differ in size");
  }
  if (cloud.hasColor() && (cloud.g.size() != n || cloud.b.size() != n)) {
    throw std::invalid_argument("writePly: r, g, b of the cloud differ in size");
  }
  if (labels && labels->size() != n) {
    throw std::invalid_argument("writePly: " + std::to_string(labels->size()) + " labels for " +
                                std::to_string(n) + " points");
  }
  using detail::PlyColumn;
  std::vector<PlyColumn> cols;
  cols.push_back({"x", false, cloud.x.data()});
  cols.push_back({"y", false, cloud.y.data()});
  cols.push_back({"z", false, cloud.z.data()});
  if (labels) {
    PlyColumn c{"label", true};
    // Label is a uint8_t enum; reading it through unsigned char is allowed aliasing.
    c.u8 = reinterpret_cast<const std::uint8_t*>(labels->data());
    cols.push_back(c);
  }
  if (cloud.hasColor()) {
    for (const auto& [name, data] : {std::pair{"red", &cloud.r}, std::pair{"green", &cloud.g},
                                     std::pair{"blue", &cloud.b}}) {
      PlyColumn c{name, true};
      c.u8 = data->data();
      cols.push_back(c);
    }
  }
  detail::writeBinaryPly(path, n, cols,
                         detail::withOriginComment(options.comments, cloud.sensor_origin),
                         options.drop_non_finite_xyz);
}

}  // namespace upd::io
