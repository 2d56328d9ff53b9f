// The data side of the figures: reading a scored PLY (or scoring a raw cloud) and the colour
// maps named in figure.h.
#include "upd/nav/figure.h"

#include "upd/core/pipeline.h"
#include "upd/io/cloud_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
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

template <class T>
double load(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return static_cast<double>(v);
}

// A vertex property's value in the row (little-endian, any PLY scalar type); NaN when absent.
double fieldAt(const char* row, const PlyLayout& l, const std::string& name) {
  const auto it = l.props.find(name);
  if (it == l.props.end()) return std::numeric_limits<double>::quiet_NaN();
  const char* p = row + it->second.first;
  const std::string& t = it->second.second;
  if (t == "float" || t == "float32") return load<float>(p);
  if (t == "double" || t == "float64") return load<double>(p);
  if (t == "char" || t == "int8") return load<std::int8_t>(p);
  if (t == "uchar" || t == "uint8") return load<std::uint8_t>(p);
  if (t == "short" || t == "int16") return load<std::int16_t>(p);
  if (t == "ushort" || t == "uint16") return load<std::uint16_t>(p);
  if (t == "int" || t == "int32") return load<std::int32_t>(p);
  return load<std::uint32_t>(p);  // uint, uint32 (plyTypeSize admits no other)
}

// A label as written (0, 1, 2); any other value (a float label edited by hand, NaN) is unknown.
core::Label labelOf(double v) {
  if (v == 0.0) return core::Label::Traversable;
  if (v == 1.0) return core::Label::NonTraversable;
  return core::Label::Unknown;
}

// A colour channel: integers clamped to 0..255, floats taken as 0..1 (as io's PLY reader does).
std::uint8_t colourByte(double v, const std::string& type) {
  if (type == "float" || type == "float32" || type == "double" || type == "float64") v *= 255.0;
  if (!(v > 0.0)) return 0;  // NaN too
  return v >= 255.0 ? 255 : static_cast<std::uint8_t>(std::lround(v));
}

ScoredCloud readScoredPly(std::istream& in, const PlyLayout& l, const std::string& path) {
  for (const char* f : {"x", "y", "z", "nx", "ny", "nz", "scalar_zeta", "scalar_label", "scalar_cost"})
    if (!l.props.count(f)) throw std::runtime_error(path + ": scored PLY has no vertex property '" + f + "'");
  if (!l.binary_le || !l.vertex_only)
    throw std::runtime_error(path + ": a scored PLY must be binary_little_endian with vertices only");
  // The vertices must be in the file before anything is allocated for them.
  const std::uint64_t bytes = io::bytesLeft(in);
  if (l.vertices > bytes / l.stride)
    throw std::runtime_error(path + ": truncated PLY (the header declares " + std::to_string(l.vertices) +
                             " vertices of " + std::to_string(l.stride) + " bytes, the file holds " +
                             std::to_string(bytes) + " bytes after it)");
  std::vector<char> data(l.vertices * l.stride);
  if (!in.read(data.data(), std::streamsize(data.size())))
    throw std::runtime_error(path + ": truncated PLY (expected " + std::to_string(l.vertices) + " vertices)");
  const bool rgb = l.props.count("red") && l.props.count("green") && l.props.count("blue");
  ScoredCloud c;
  for (std::size_t i = 0; i < l.vertices; ++i) {
    const char* row = data.data() + i * l.stride;
    const auto f = [&](const char* name) { return static_cast<float>(fieldAt(row, l, name)); };
    const Eigen::Vector3f p(f("x"), f("y"), f("z"));
    if (!p.allFinite()) continue;
    c.points.push_back(p);
    c.normals.emplace_back(f("nx"), f("ny"), f("nz"));
    c.zeta.push_back(f("scalar_zeta"));
    c.cost.push_back(f("scalar_cost"));
    c.label.push_back(labelOf(fieldAt(row, l, "scalar_label")));
    if (rgb) {
      std::array<std::uint8_t, 3> col{};
      for (int k = 0; k < 3; ++k) {
        const char* name = k == 0 ? "red" : k == 1 ? "green" : "blue";
        col[k] = colourByte(fieldAt(row, l, name), l.props.at(name).second);
      }
      c.rgb.push_back(col);
    }
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
