// The data side of the figures: reading a scored PLY (or scoring a raw cloud) and the colour
// maps named in figure.h.
#include "upd/nav/figure.h"

#include "upd/core/pipeline.h"
#include "upd/io/cloud_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace upd::nav {
namespace {

ScoredCloud fromScoredPly(const io::ScoredPly& f) {
  const core::PointCloud& pc = f.cloud;
  ScoredCloud c;
  for (std::size_t i = 0; i < pc.size(); ++i) {
    const Eigen::Vector3f p(pc.x[i], pc.y[i], pc.z[i]);
    if (!p.allFinite()) continue;
    c.points.push_back(p);
    c.normals.emplace_back(f.nx[i], f.ny[i], f.nz[i]);
    c.zeta.push_back(f.zeta[i]);
    c.cost.push_back(f.cost[i]);
    c.label.push_back(f.label[i]);
    if (pc.hasColor()) c.rgb.push_back({pc.r[i], pc.g[i], pc.b[i]});
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
  bool scored = false;
  if (io::lowerExtension(path) == ".ply") {
    const std::vector<std::string> names = io::plyVertexProperties(path);
    scored = std::find(names.begin(), names.end(), "scalar_zeta") != names.end();
  }
  ScoredCloud c = scored ? fromScoredPly(io::readScoredPly(path)) : scoreRawCloud(path, up);
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
