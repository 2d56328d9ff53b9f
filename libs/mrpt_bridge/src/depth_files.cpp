#include "upd/mrpt_bridge/depth_files.h"

#include "upd/io/atomic_file.h"
#include "upd/io/whole_file.h"
#include "upd/io/png_gray16.h"
#include "yaml_text.h"

#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdint>
#include <ostream>
#include <stdexcept>
#include <vector>

namespace upd::mrpt_bridge {

namespace {

[[noreturn]] void fail(const std::string& file, const std::string& why) {
  throw std::runtime_error("calibration " + file + ": " + why);
}

// The values of a matrix field: ROS/OpenCV `{rows, cols, data: [...]}` or an OpenCV matrix.
std::vector<double> matrixValues(const cv::FileNode& node, const std::string& file,
                                 const std::string& key, std::size_t expected) {
  std::vector<double> v;
  try {  // (OpenCV throws where an element is not a number)
    if (node.isMap() && node["data"].isSeq()) {
      node["data"] >> v;
    } else if (node.isSeq()) {
      node >> v;
    } else {
      cv::Mat m;
      node >> m;
      m.reshape(1, 1).convertTo(v, CV_64F);
    }
  } catch (const cv::Exception& e) {
    fail(file, "'" + key + "' is not a list of numbers (" + e.err + ")");
  }
  if (v.size() != expected) {
    fail(file, "'" + key + "' has " + std::to_string(v.size()) + " values, expected " +
                   std::to_string(expected));
  }
  for (double x : v) {
    if (!std::isfinite(x)) fail(file, "'" + key + "' holds a value that is not finite");
  }
  return v;
}

int intField(const cv::FileStorage& fs, const std::string& file, const char* key) {
  const cv::FileNode n = fs[key];
  if (n.empty() || !n.isInt()) fail(file, std::string("no integer '") + key + "'");
  return static_cast<int>(n);
}

Eigen::Isometry3d localTransform(const cv::FileNode& node, const std::string& file) {
  const std::vector<double> v = matrixValues(node, file, "local_transform", 12);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) T.linear()(r, c) = v[r * 4 + c];
    T.translation()(r) = v[r * 4 + 3];
  }
  const Eigen::Matrix3d R = T.linear();
  if (!(R * R.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-3)) {
    fail(file, "'local_transform' is not a rotation and a translation");
  }
  // Re-orthonormalize the rotation stored with 8 digits.
  T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  return T;
}

}  // namespace

namespace {
DepthCalibration readCalibration(const std::string& yaml_path) {
  const cv::FileStorage fs = openCheckedYaml(yaml_path, "calibration");
  DepthCalibration c;
  c.K.width = intField(fs, yaml_path, "image_width");
  c.K.height = intField(fs, yaml_path, "image_height");
  const cv::FileNode km = fs["camera_matrix"];
  if (km.empty()) fail(yaml_path, "no 'camera_matrix'");
  const std::vector<double> k = matrixValues(km, yaml_path, "camera_matrix", 9);
  c.K.fx = k[0];
  c.K.cx = k[2];
  c.K.fy = k[4];
  c.K.cy = k[5];
  if (!(c.K.fx > 0)) fail(yaml_path, "camera_matrix fx = " + std::to_string(c.K.fx) + ": must be > 0");
  if (!(c.K.fy > 0)) fail(yaml_path, "camera_matrix fy = " + std::to_string(c.K.fy) + ": must be > 0");
  if (c.K.width <= 0 || c.K.height <= 0) {
    fail(yaml_path, "image_width x image_height = " + std::to_string(c.K.width) + " x " +
                        std::to_string(c.K.height) + ": must be > 0");
  }
  const cv::FileNode dist = fs["distortion_coefficients"];
  if (!dist.empty()) {
    std::vector<double> d;
    try {
      if (dist.isMap() && dist["data"].isSeq()) dist["data"] >> d;
    } catch (const cv::Exception& e) {
      fail(yaml_path, "'distortion_coefficients' is not a list of numbers (" + e.err + ")");
    }
    for (double x : d) c.has_distortion = c.has_distortion || x != 0.0;
  }
  const cv::FileNode lt = fs["local_transform"];
  if (!lt.empty()) c.camera_on_robot = localTransform(lt, yaml_path);
  return c;
}
}  // namespace

DepthCalibration loadDepthCalibration(const std::string& yaml_path) {
  // (What the fields' own checks did not foresee: OpenCV's errors, and the standard library's
  // that its parser lets through, as one line naming the file.)
  try {
    return readCalibration(yaml_path);
  } catch (const std::runtime_error&) {
    throw;  // (ours, naming the file and field)
  } catch (const cv::Exception& e) {
    fail(yaml_path, "not a calibration OpenCV can read (" + e.err + ")");
  } catch (const std::exception&) {
    fail(yaml_path, "not a calibration OpenCV can read");
  }
}

core::DepthImage readDepthPng(const std::string& png_path, double metres_per_unit) {
  if (!(metres_per_unit > 0) || !std::isfinite(metres_per_unit)) {
    throw std::invalid_argument("depth scale = " + std::to_string(metres_per_unit) +
                                " m per unit: must be > 0");
  }
  const auto bad = [&](const std::string& why) {
    return std::runtime_error("depth image " + png_path + ": " + why);
  };
  // (At most 128 MB: the largest image read, 2^25 pixels of 2 bytes, is 64 MB even stored.)
  std::string bytes;
  try {
    bytes = io::readWholeFile(png_path, std::uintmax_t{1} << 27);
  } catch (const std::runtime_error& e) {
    throw bad(e.what());
  }
  // (libpng itself, not through OpenCV: its errors come back as text, where OpenCV's decoder
  // lets libpng print them on stderr; and the header's size is checked before any allocation,
  // where OpenCV allocates up to 2^30 pixels.)
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const io::Gray16 img =
      io::decodeGray16(data, bytes.size(), kMaxDepthSide, kMaxDepthPixels);
  const std::string why = io::whyNotGray16(img, kMaxDepthSide, kMaxDepthPixels);
  if (!why.empty()) throw bad(why);
  core::DepthImage d;
  d.width = static_cast<int>(img.width);
  d.height = static_cast<int>(img.height);
  d.depth_m.resize(img.pixels.size());
  for (std::size_t i = 0; i < img.pixels.size(); ++i) {
    d.depth_m[i] = static_cast<float>(img.pixels[i] * metres_per_unit);
  }
  return d;
}

void writeDepthPng(const std::string& png_path, const core::DepthImage& depth,
                   double metres_per_unit) {
  cv::Mat img(depth.height, depth.width, CV_16UC1);
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      const double units = std::round(depth.at(u, v) / metres_per_unit);
      img.at<std::uint16_t>(v, u) =
          std::isfinite(units) && units > 0 && units <= 65535 ? static_cast<std::uint16_t>(units) : 0;
    }
  }
  std::vector<unsigned char> bytes;
  if (!cv::imencode(".png", img, bytes)) {
    throw std::runtime_error("depth image " + png_path + ": PNG encoding failed");
  }
  io::writeFileAtomically(png_path, [&](std::ostream& os) {
    os.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  });
}

core::CameraIntrinsics tumIntrinsics(const std::string& name) {
  core::CameraIntrinsics K;  // 640 x 480, the ROS default
  if (name == "ros") return K;
  if (name == "freiburg1") {
    K.fx = 517.3, K.fy = 516.5, K.cx = 318.6, K.cy = 255.3;
  } else if (name == "freiburg2") {
    K.fx = 520.9, K.fy = 521.0, K.cx = 325.1, K.cy = 249.7;
  } else if (name == "freiburg3") {
    K.fx = 535.4, K.fy = 539.2, K.cx = 320.1, K.cy = 247.6;
  } else {
    throw std::invalid_argument("TUM camera '" + name +
                                "': expected freiburg1, freiburg2, freiburg3 or ros");
  }
  return K;
}

}  // namespace upd::mrpt_bridge
