#include "upd/io/cloud_io.h"

#include "io_detail.h"
#include "ply_detail.h"

#include <cstdio>
#include <limits>
#include <stdexcept>
#include <utility>

namespace upd::io {

namespace detail {

std::vector<std::string> withOriginComment(std::vector<std::string> comments,
                                           const Eigen::Vector3f& origin) {
  if (origin.isZero(0.f)) return comments;  // the default: nothing to record
  char line[96];
  std::snprintf(line, sizeof line, "sensor_origin %.9g %.9g %.9g", origin.x(), origin.y(), origin.z());
  comments.emplace_back(line);
  return comments;
}

}  // namespace detail

namespace {

template <class T>
void requireSize(const ArrayView<T>& v, const char* name, std::size_t n, bool optional) {
  if (v.size != 0 && v.data == nullptr) {
    throw std::invalid_argument(std::string("ScoredPoints.") + name + " has a size but no data");
  }
  if ((optional && v.empty()) || v.size == n) return;
  throw std::invalid_argument(std::string("ScoredPoints.") + name + " has " +
                              std::to_string(v.size) + " values; expected " +
                              (optional ? "0 or " : "") + std::to_string(n));
}

}  // namespace

void ScoredPoints::validate() const {
  const std::size_t n = size();
  requireSize(x, "x", n, false);
  requireSize(y, "y", n, false);
  requireSize(z, "z", n, false);
  requireSize(nx, "nx", n, true);
  requireSize(ny, "ny", n, true);
  requireSize(nz, "nz", n, true);
  requireSize(rx, "rx", n, true);
  requireSize(ry, "ry", n, true);
  requireSize(rz, "rz", n, true);
  requireSize(zeta, "zeta", n, true);
  requireSize(label, "label", n, true);
  requireSize(cost, "cost", n, true);
  requireSize(r, "r", n, true);
  requireSize(g, "g", n, true);
  requireSize(b, "b", n, true);
  if (r.empty() != g.empty() || r.empty() != b.empty()) {
    throw std::invalid_argument("ScoredPoints.r/g/b must be all present or all absent");
  }
  if ((width != 0 || height != 0) && width * height != size()) {
    throw std::invalid_argument("ScoredPoints.width x height (" + std::to_string(width) + " x " +
                                std::to_string(height) + ") is not the point count " +
                                std::to_string(size()));
  }
}

ScoredPoints scoredPointsOf(const core::PipelineResult& result) {
  ScoredPoints s;
  const core::PointCloud& c = result.cloud;
  s.x = c.x;
  s.y = c.y;
  s.z = c.z;
  s.nx = result.normals.nx;
  s.ny = result.normals.ny;
  s.nz = result.normals.nz;
  s.rx = result.upd.rx;
  s.ry = result.upd.ry;
  s.rz = result.upd.rz;
  s.zeta = result.upd.zeta;
  s.label = result.classes.label;
  s.cost = result.classes.cost;
  if (c.isOrganized()) {
    s.width = c.width;
    s.height = c.height;
  }
  if (c.hasColor()) {
    s.r = c.r;
    s.g = c.g;
    s.b = c.b;
  }
  return s;
}

const std::vector<std::string>& scoredPlyProperties() {
  static const std::vector<std::string> kNames = {
      "x",         "y",           "z",            "nx",          "ny",     "nz",     "scalar_rx",
      "scalar_ry", "scalar_rz",   "scalar_zeta",  "scalar_label", "scalar_cost", "quality"};
  return kNames;
}

void writeScoredPly(const std::string& path, const ScoredPoints& p,
                    const ScoredPlyOptions& options) {
  p.validate();
  using detail::PlyColumn;
  auto floatColumn = [](const char* name, const ArrayView<float>& v) {
    PlyColumn c{name, false};
    c.f = v.empty() ? nullptr : v.data;
    return c;
  };
  auto byteColumn = [](const char* name, const std::uint8_t* data, std::uint8_t fill) {
    PlyColumn c{name, true};
    c.u8 = data;
    c.fill_u8 = fill;
    return c;
  };
  std::vector<PlyColumn> cols = {
      floatColumn("x", p.x),   floatColumn("y", p.y),   floatColumn("z", p.z),
      floatColumn("nx", p.nx), floatColumn("ny", p.ny), floatColumn("nz", p.nz),
      floatColumn("scalar_rx", p.rx), floatColumn("scalar_ry", p.ry),
      floatColumn("scalar_rz", p.rz), floatColumn("scalar_zeta", p.zeta),
      // Label is a uint8_t enum; reading it through unsigned char is allowed aliasing.
      byteColumn("scalar_label",
                 p.label.empty() ? nullptr : reinterpret_cast<const std::uint8_t*>(p.label.data),
                 static_cast<std::uint8_t>(core::Label::Unknown)),
      floatColumn("scalar_cost", p.cost), floatColumn("quality", p.zeta)};
  if (!p.r.empty()) {
    cols.push_back(byteColumn("red", p.r.data, 0));
    cols.push_back(byteColumn("green", p.g.data, 0));
    cols.push_back(byteColumn("blue", p.b.data, 0));
  }
  std::vector<std::string> comments = options.comments;
  if (options.organized && p.height > 1) {
    comments.push_back("width " + std::to_string(p.width));
    comments.push_back("height " + std::to_string(p.height));
  }
  detail::writeBinaryPly(path, p.size(), cols, comments, !options.organized);
}

ScoredPly readScoredPly(const std::string& path) {
  // The columns read beside the cloud: the first six are required, r is read when present.
  static const std::vector<std::string> kColumns = {"nx",          "ny",           "nz",
                                                    "scalar_zeta", "scalar_label", "scalar_cost",
                                                    "scalar_rx",   "scalar_ry",    "scalar_rz"};
  detail::PlyVertices v = detail::readPlyVertices(path, kColumns);
  for (std::size_t k = 0; k < 6; ++k) {
    if (!v.has_extra[k]) {
      throw detail::fileError(path, "not a scored PLY: no vertex property '" + kColumns[k] + "'");
    }
  }
  const std::size_t n = v.cloud.size();
  for (std::size_t k = 6; k < kColumns.size(); ++k) {
    if (!v.has_extra[k]) v.extra[k].assign(n, std::numeric_limits<float>::quiet_NaN());
  }
  ScoredPly out;
  out.cloud = std::move(v.cloud);
  out.nx = std::move(v.extra[0]);
  out.ny = std::move(v.extra[1]);
  out.nz = std::move(v.extra[2]);
  out.zeta = std::move(v.extra[3]);
  out.cost = std::move(v.extra[5]);
  out.rx = std::move(v.extra[6]);
  out.ry = std::move(v.extra[7]);
  out.rz = std::move(v.extra[8]);
  out.label.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float l = v.extra[4][i];
    out.label[i] = l == 0.f   ? core::Label::Traversable
                   : l == 1.f ? core::Label::NonTraversable
                              : core::Label::Unknown;
  }
  return out;
}

void writeScoredPly(const std::string& path, const core::PipelineResult& result,
                    const ScoredPlyOptions& options) {
  ScoredPlyOptions with_origin = options;
  with_origin.comments = detail::withOriginComment(options.comments, result.cloud.sensor_origin);
  writeScoredPly(path, scoredPointsOf(result), with_origin);
}

}  // namespace upd::io
