#include "upd/io/ros_map.h"

#include "upd/io/atomic_file.h"

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
  const int ix = static_cast<int>(std::floor((x - origin_xy.x()) / resolution_m));
  const int iy = static_cast<int>(std::floor((y - origin_xy.y()) / resolution_m));
  if (ix < 0 || iy < 0 || ix >= width || iy >= height) return core::Label::Unknown;
  return at(ix, iy);
}

void writeRosMap(const RosMap& map, const std::string& yaml_path) {
  if (map.width < 0 || map.height < 0 ||
      map.labels.size() != static_cast<std::size_t>(map.width) * map.height) {
    throw std::invalid_argument(
        "writeRosMap " + yaml_path + ": " + std::to_string(map.labels.size()) + " labels for a " +
        std::to_string(map.width) + " x " + std::to_string(map.height) + " map");
  }
  if (!(map.resolution_m > 0) || !std::isfinite(map.resolution_m)) {
    throw std::invalid_argument("writeRosMap " + yaml_path + ": resolution_m = " +
                                std::to_string(map.resolution_m) + ": must be > 0");
  }
  const fs::path yaml(yaml_path);
  const std::string pgm_path = (yaml.parent_path() / yaml.stem()).string() + ".pgm";
  const int w = map.width, h = map.height;
  std::string pixels(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), '\0');
  for (int row = 0; row < h; ++row) {
    const int iy = h - 1 - row;  // image row 0 is the top: y max
    for (int ix = 0; ix < w; ++ix) {
      pixels[static_cast<std::size_t>(row) * w + ix] =
          static_cast<char>(rosPixelOf(map.at(ix, iy)));
    }
  }
  writeFileAtomically(pgm_path, [&](std::ostream& os) {
    os << "P5\n" << w << " " << h << "\n255\n";
    os.write(pixels.data(), static_cast<std::streamsize>(pixels.size()));
  });
  writeFileAtomically(yaml_path, [&](std::ostream& os) {
    os << std::setprecision(12) << "image: " << fs::path(pgm_path).filename().string() << "\n"
       << "resolution: " << map.resolution_m << "\n"
       << "origin: [" << map.origin_xy.x() << ", " << map.origin_xy.y() << ", 0.0]\n"
       << "negate: 0\n"
       << "occupied_thresh: 0.65\n"
       << "free_thresh: 0.196\n"
       << "mode: trinary\n";
  });
}

namespace {

// image, resolution and origin from the YAML; returns the image's file name.
std::string readRosYaml(const std::string& yaml_path, RosMap& map) {
  std::ifstream in(yaml_path);
  if (!in) throw std::runtime_error("ROS map " + yaml_path + ": cannot be opened");
  std::string line, image;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(0, colon);
    std::string value = line.substr(colon + 1);
    if (key == "image") {
      std::istringstream(value) >> image;
    } else if (key == "resolution") {
      map.resolution_m = std::stod(value);
    } else if (key == "origin") {
      std::replace_if(
          value.begin(), value.end(), [](char c) { return c == '[' || c == ']' || c == ','; }, ' ');
      std::istringstream(value) >> map.origin_xy.x() >> map.origin_xy.y();
    }
  }
  if (image.empty()) throw std::runtime_error("ROS map " + yaml_path + ": no image key");
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
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(map.width) * map.height);
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
