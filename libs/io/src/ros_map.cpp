#include "upd/io/ros_map.h"

#include "upd/io/atomic_file.h"

#include "io_detail.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace upd::io {

namespace fs = std::filesystem;

std::uint8_t rosPixelOf(core::Label label) {
  switch (label) {
    case core::Label::NonTraversable:
      return kRosOccupied;
    case core::Label::Traversable:
      return kRosFree;
    case core::Label::Unknown:
      break;
  }
  return kRosUnknown;
}

core::Label labelOfRosPixel(std::uint8_t value) {
  return value < 100 ? core::Label::NonTraversable : value > 250 ? core::Label::Traversable : core::Label::Unknown;
}

core::Label RosMap::labelAt(double x, double y) const {
  // Compared in double before the conversion: a position far off the map has no int cell.
  const double fx = std::floor((x - origin_xy.x()) / resolution_m);
  const double fy = std::floor((y - origin_xy.y()) / resolution_m);
  if (!(fx >= 0 && fy >= 0 && fx < width && fy < height)) return core::Label::Unknown;
  return at(static_cast<int>(fx), static_cast<int>(fy));
}

namespace {

void checkMapShape(const std::string& yaml_path, int width, int height, std::size_t cells,
                   double resolution_m) {
  if (width < 0 || height < 0 || cells != static_cast<std::size_t>(width) * height) {
    throw std::invalid_argument("writeRosMap " + yaml_path + ": " + std::to_string(cells) +
                                " cells for a " + std::to_string(width) + " x " +
                                std::to_string(height) + " map");
  }
  if (!(resolution_m > 0) || !std::isfinite(resolution_m)) {
    throw std::invalid_argument("writeRosMap " + yaml_path + ": resolution_m = " +
                                std::to_string(resolution_m) + ": must be > 0");
  }
}

// The PGM (pixel_of(ix, iy) per cell, row 0 = y max) and then the YAML naming it, each
// atomically.
template <class PixelOf>
void writePgmAndYaml(const std::string& yaml_path, int w, int h, double resolution_m,
                     const Eigen::Vector2d& origin_xy, const char* mode, PixelOf pixel_of) {
  const fs::path yaml(yaml_path);
  const std::string pgm_path = (yaml.parent_path() / yaml.stem()).string() + ".pgm";
  std::string pixels(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), '\0');
  for (int row = 0; row < h; ++row) {
    const int iy = h - 1 - row;  // image row 0 is the top: y max
    for (int ix = 0; ix < w; ++ix) {
      pixels[static_cast<std::size_t>(row) * w + ix] = static_cast<char>(pixel_of(ix, iy));
    }
  }
  writeFileAtomically(pgm_path, [&](std::ostream& os) {
    os << "P5\n" << w << " " << h << "\n255\n";
    os.write(pixels.data(), static_cast<std::streamsize>(pixels.size()));
  });
  writeFileAtomically(yaml_path, [&](std::ostream& os) {
    os << std::setprecision(12) << "image: " << fs::path(pgm_path).filename().string() << "\n"
       << "resolution: " << resolution_m << "\n"
       << "origin: [" << origin_xy.x() << ", " << origin_xy.y() << ", 0.0]\n"
       << "negate: 0\n"
       << "occupied_thresh: 0.65\n"
       << "free_thresh: 0.196\n"
       << "mode: " << mode << "\n";
  });
}

}  // namespace

void writeRosMap(const RosMap& map, const std::string& yaml_path) {
  checkMapShape(yaml_path, map.width, map.height, map.labels.size(), map.resolution_m);
  writePgmAndYaml(yaml_path, map.width, map.height, map.resolution_m, map.origin_xy, "trinary",
                  [&](int ix, int iy) { return rosPixelOf(map.at(ix, iy)); });
}

std::uint8_t rosScalePixelOf(float p_occupied) {
  const float p = std::isnan(p_occupied) ? 0.5f : std::clamp(p_occupied, 0.f, 1.f);
  return static_cast<std::uint8_t>(std::lround(255.f * (1.f - p)));
}

void writeRosScaleMap(const RosScaleMap& map, const std::string& yaml_path) {
  checkMapShape(yaml_path, map.width, map.height, map.p_occupied.size(), map.resolution_m);
  writePgmAndYaml(yaml_path, map.width, map.height, map.resolution_m, map.origin_xy, "scale",
                  [&](int ix, int iy) {
                    return rosScalePixelOf(map.p_occupied[static_cast<std::size_t>(iy) * map.width + ix]);
                  });
}

namespace {

// image, resolution and origin from the YAML; returns the image's file name. The resolution
// must be a number > 0 and the origin's x and y finite numbers (the map's cells follow from them).
std::string readRosYaml(const std::string& yaml_path, RosMap& map) {
  std::ifstream in(yaml_path);
  if (!in) throw std::runtime_error("ROS map " + yaml_path + ": cannot be opened");
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error("ROS map " + yaml_path + ": " + why);
  };
  std::string line, image;
  bool resolution = false, origin = false;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(0, colon);
    std::string value = line.substr(colon + 1);
    if (key == "image") {
      std::istringstream(value) >> image;
    } else if (key == "resolution") {
      std::istringstream is(value);
      std::string rest;
      if (!(is >> map.resolution_m) || (is >> rest) || !std::isfinite(map.resolution_m) ||
          !(map.resolution_m > 0)) {
        const auto first = value.find_first_not_of(' ');
        fail("resolution '" + (first == std::string::npos ? "" : value.substr(first)) +
             "' is not a number > 0");
      }
      resolution = true;
    } else if (key == "origin") {
      std::replace_if(
          value.begin(), value.end(), [](char c) { return c == '[' || c == ']' || c == ','; }, ' ');
      if (!(std::istringstream(value) >> map.origin_xy.x() >> map.origin_xy.y()) ||
          !map.origin_xy.allFinite()) {
        fail("origin is not [x, y, yaw] of finite numbers");
      }
      origin = true;
    }
  }
  if (image.empty()) fail("no image key");
  if (!resolution) fail("no resolution key");
  if (!origin) fail("no origin key");
  return image;
}

}  // namespace

RosMap readRosMap(const std::string& yaml_path) {
  RosMap map;
  const std::string image = readRosYaml(yaml_path, map);
  const fs::path pgm_path = fs::path(yaml_path).parent_path() / image;
  std::ifstream pgm(pgm_path, std::ios::binary);
  std::string magic;
  int maxval = 0;
  if (!(pgm >> magic >> map.width >> map.height >> maxval) || magic != "P5" || maxval != 255 ||
      map.width < 0 || map.height < 0) {
    throw std::runtime_error("ROS map " + pgm_path.string() + ": not an 8-bit P5 PGM");
  }
  pgm.get();
  // The pixels must be in the file before they are allocated (a damaged header's size).
  const std::uint64_t bytes = detail::bytesLeft(pgm);
  const std::size_t cells = static_cast<std::size_t>(map.width) * map.height;
  if (cells > bytes) {
    throw std::runtime_error("ROS map " + pgm_path.string() + ": truncated (" +
                             std::to_string(map.width) + " x " + std::to_string(map.height) +
                             " pixels, " + std::to_string(bytes) + " bytes after the header)");
  }
  std::vector<std::uint8_t> pixels(cells);
  if (!pgm.read(reinterpret_cast<char*>(pixels.data()),
                static_cast<std::streamsize>(pixels.size()))) {
    throw std::runtime_error("ROS map " + pgm_path.string() + ": truncated");
  }
  map.labels.resize(pixels.size());
  for (int row = 0; row < map.height; ++row) {
    const int iy = map.height - 1 - row;
    for (int ix = 0; ix < map.width; ++ix) {
      map.labels[static_cast<std::size_t>(iy) * map.width + ix] =
          labelOfRosPixel(pixels[static_cast<std::size_t>(row) * map.width + ix]);
    }
  }
  return map;
}

}  // namespace upd::io
