// The data side of the figures: reading a scored PLY (or scoring a raw cloud) and the colour
// maps named in figure.h.
#include "upd/nav/figure.h"

#include "upd/core/pipeline.h"
#include "upd/io/cloud_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

namespace upd::nav {
namespace {

std::size_t plyTypeSize(const std::string& t) {
  static const std::map<std::string, std::size_t> sizes = {
      {"char", 1},  {"uchar", 1},  {"int8", 1},    {"uint8", 1},  {"short", 2},
      {"ushort", 2}, {"int16", 2}, {"uint16", 2},  {"int", 4},    {"uint", 4},
      {"int32", 4}, {"uint32", 4}, {"float", 4},   {"float32", 4}, {"double", 8},
      {"float64", 8}};
  const auto it = sizes.find(t);
  return it == sizes.end() ? 0 : it->second;
}

struct PlyLayout {
  bool binary_le = false;
  std::size_t vertices = 0, stride = 0;
  std::map<std::string, std::pair<std::size_t, std::string>> props;  // name -> offset, type
  bool vertex_only = true;
};

PlyLayout readPlyHeader(std::istream& in, const std::string& path) {
  PlyLayout l;
  std::string line, element;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line == "end_header") return l;
    std::istringstream ss(line);
    std::string word;
    ss >> word;
    if (word == "format") {
      std::string f;
      ss >> f;
      l.binary_le = f == "binary_little_endian";
    } else if (word == "element") {
      std::size_t n = 0;
      ss >> element >> n;
      if (element == "vertex") l.vertices = n;
      else if (n > 0) l.vertex_only = false;
    } else if (word == "property" && element == "vertex") {
      std::string type, name;
      ss >> type >> name;
      const std::size_t size = plyTypeSize(type);
      if (size == 0) throw std::runtime_error(path + ": unsupported PLY vertex property type '" + type + "'");
      l.props[name] = {l.stride, type};
      l.stride += size;
    }
  }
  throw std::runtime_error(path + ": PLY header has no end_header");
}

float fieldAt(const char* row, const PlyLayout& l, const std::string& name) {
  const auto it = l.props.find(name);
  if (it == l.props.end()) return std::numeric_limits<float>::quiet_NaN();
  const char* p = row + it->second.first;
  if (it->second.second == "float" || it->second.second == "float32") {
    float v;
    std::memcpy(&v, p, 4);
    return v;
  }
  return float(static_cast<unsigned char>(*p));  // the scored PLY's only other type: uchar label
}

ScoredCloud readScoredPly(std::istream& in, const PlyLayout& l, const std::string& path) {
  for (const char* f : {"x", "y", "z", "nx", "ny", "nz", "scalar_zeta", "scalar_label", "scalar_cost"})
    if (!l.props.count(f)) throw std::runtime_error(path + ": scored PLY has no vertex property '" + f + "'");
  if (!l.binary_le || !l.vertex_only)
    throw std::runtime_error(path + ": a scored PLY must be binary_little_endian with vertices only");
  std::vector<char> data(l.vertices * l.stride);
  if (!in.read(data.data(), std::streamsize(data.size())))
    throw std::runtime_error(path + ": truncated PLY (expected " + std::to_string(l.vertices) + " vertices)");
  ScoredCloud c;
  for (std::size_t i = 0; i < l.vertices; ++i) {
    const char* row = data.data() + i * l.stride;
    const Eigen::Vector3f p(fieldAt(row, l, "x"), fieldAt(row, l, "y"), fieldAt(row, l, "z"));
    if (!p.allFinite()) continue;
    c.points.push_back(p);
    c.normals.emplace_back(fieldAt(row, l, "nx"), fieldAt(row, l, "ny"), fieldAt(row, l, "nz"));
    c.zeta.push_back(fieldAt(row, l, "scalar_zeta"));
    c.cost.push_back(fieldAt(row, l, "scalar_cost"));
    const float lab = fieldAt(row, l, "scalar_label");
    c.label.push_back(lab <= 2.0f ? core::Label(std::uint8_t(lab)) : core::Label::Unknown);
    if (l.props.count("red") && l.props.count("green") && l.props.count("blue"))
      c.rgb.push_back({std::uint8_t(fieldAt(row, l, "red")), std::uint8_t(fieldAt(row, l, "green")),
                       std::uint8_t(fieldAt(row, l, "blue"))});
  }
  return c;
}

ScoredCloud scoreRawCloud(const std::string& path, const Eigen::Vector3f& up) {
  const core::PointCloud raw = io::readCloud(path);
  core::PipelineParams params;
  params.up = up.normalized();
  params.validate();
  const core::PipelineResult res = core::runPipeline(raw, params);
  ScoredCloud c;
  for (std::size_t i = 0; i < res.cloud.size(); ++i) {
    const Eigen::Vector3f p(res.cloud.x[i], res.cloud.y[i], res.cloud.z[i]);
    if (!p.allFinite()) continue;
    c.points.push_back(p);
    c.normals.emplace_back(res.normals.nx[i], res.normals.ny[i], res.normals.nz[i]);
    c.zeta.push_back(res.upd.zeta[i]);
    c.cost.push_back(res.classes.cost[i]);
    c.label.push_back(res.classes.label[i]);
    if (res.cloud.hasColor()) c.rgb.push_back({res.cloud.r[i], res.cloud.g[i], res.cloud.b[i]});
  }
  return c;
}

}  // namespace

FigureColor parseFigureColor(const std::string& name) {
  if (name == "zeta") return FigureColor::Zeta;
  if (name == "label") return FigureColor::Label;
  if (name == "cost") return FigureColor::Cost;
  if (name == "slope") return FigureColor::Slope;
  if (name == "height") return FigureColor::Height;
  if (name == "rgb") return FigureColor::Rgb;
  throw std::invalid_argument("unknown colouring '" + name + "' (zeta, label, cost, slope, height, rgb)");
}

ScoredCloud loadScoredCloud(const std::string& path, const Eigen::Vector3f& up) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open the file");
  ScoredCloud c;
  if (io::lowerExtension(path) == ".ply") {
    std::string magic;
    std::getline(in, magic);
    if (magic.rfind("ply", 0) != 0) throw std::runtime_error(path + ": not a PLY file");
    const PlyLayout l = readPlyHeader(in, path);
    c = l.props.count("scalar_zeta") ? readScoredPly(in, l, path) : scoreRawCloud(path, up);
  } else {
    c = scoreRawCloud(path, up);
  }
  if (c.size() == 0) throw std::runtime_error(path + ": no valid points to draw");
  return c;
}

Rgb zetaColor(float zeta) {
  if (!(zeta == zeta)) return {150, 150, 150};
  const float lo = std::sqrt(2.0f) / 2.0f;
  const float t = std::clamp((1.0f - zeta) / (1.0f - lo), 0.0f, 1.0f);
  // green (40, 170, 60) -> teal (20, 150, 170) at t = 0.5 -> blue (30, 60, 220)
  auto mix = [](float a, float b, float u) { return std::uint8_t(std::lround(a + (b - a) * u)); };
  if (t < 0.5f) {
    const float u = t / 0.5f;
    return {mix(40, 20, u), mix(170, 150, u), mix(60, 170, u)};
  }
  const float u = (t - 0.5f) / 0.5f;
  return {mix(20, 30, u), mix(150, 60, u), mix(170, 220, u)};
}

}  // namespace upd::nav
