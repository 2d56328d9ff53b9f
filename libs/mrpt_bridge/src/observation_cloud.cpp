#include "upd/mrpt_bridge/observation_cloud.h"

#include "mrpt_util.h"
#include "observation_stereo.h"
#include "upd/core/params.h"
#include "upd/mrpt_bridge/pose_source.h"

#include <opencv2/core.hpp>

#include <mrpt/img/CImage.h>
#include <mrpt/maps/CColouredPointsMap.h>
#include <mrpt/maps/CPointsMapXYZI.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/obs/VelodyneCalibration.h>
#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

namespace upd::mrpt_bridge {

void SourceParams::validate() const {
  const char* o = "SourceParams";
  core::requireParam(std::isfinite(lidar_min_range_m) && lidar_min_range_m >= 0, o, "lidar_min_range_m",
               lidar_min_range_m, "must be >= 0");
  core::requireParam(std::isfinite(lidar_max_range_m) && lidar_max_range_m > lidar_min_range_m, o,
               "lidar_max_range_m", lidar_max_range_m, "must be > lidar_min_range_m");
  core::requireParam(std::isfinite(stereo_fx_px) && stereo_fx_px >= 0, o, "stereo_fx_px", stereo_fx_px,
               "must be >= 0 (0 = calibration from the observation)");
  if (hasStereoCalibration()) {
    core::requireParam(std::isfinite(stereo_fy_px) && stereo_fy_px > 0, o, "stereo_fy_px", stereo_fy_px,
                 "must be > 0 when stereo_fx_px is set");
    core::requireParam(std::isfinite(stereo_cx_px) && stereo_cx_px > 0, o, "stereo_cx_px", stereo_cx_px,
                 "must be > 0 when stereo_fx_px is set");
    core::requireParam(std::isfinite(stereo_cy_px) && stereo_cy_px > 0, o, "stereo_cy_px", stereo_cy_px,
                 "must be > 0 when stereo_fx_px is set");
    core::requireParam(std::isfinite(stereo_baseline_m) && stereo_baseline_m > 0, o, "stereo_baseline_m",
                 stereo_baseline_m, "must be > 0 when stereo_fx_px is set");
  }
  stereo.validate();
}

namespace {

struct Transform {
  Eigen::Matrix3f r;
  Eigen::Vector3f t;
  explicit Transform(const Eigen::Isometry3d& iso)
      : r(iso.linear().cast<float>()), t(iso.translation().cast<float>()) {}
  Eigen::Vector3f operator()(const Eigen::Vector3f& p) const { return r * p + t; }
};

void setPoint(core::PointCloud& c, std::size_t i, const Eigen::Vector3f& p) {
  c.x[i] = p.x();
  c.y[i] = p.y();
  c.z[i] = p.z();
}

// The points of one row of a range image in the robot frame: NaN where raw is 0 (no return),
// else the pixel's unit ray (kx, ky, kz) times raw * units moved by robot_from_sensor. No
// branch, so that the loop vectorizes.
void rangeRow(const std::uint16_t* __restrict raw, float units, const float* __restrict kx,
              const float* __restrict ky, const float* __restrict kz,
              const Transform& robot_from_sensor, int w, float* __restrict x,
              float* __restrict y, float* __restrict z) {
  const Transform tf = robot_from_sensor;  // (a local copy: not reloaded after each store)
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int u = 0; u < w; ++u) {
    // (NaN carried through the products and sums to every coordinate; the select is between
    // two values, not an arithmetic result, so that it needs no branch.)
    const float range = static_cast<float>(raw[u]) * (raw[u] != 0 ? units : nan);
    const Eigen::Vector3f p = tf(Eigen::Vector3f(kx[u] * range, ky[u] * range, kz[u] * range));
    x[u] = p.x(), y[u] = p.y(), z[u] = p.z();
  }
}

void allocateColor(core::PointCloud& c) {
  c.r.assign(c.size(), 255);
  c.g.assign(c.size(), 255);
  c.b.assign(c.size(), 255);
}

// Colour of pixel (u, v) of an 8-bit grey/BGR/BGRA image.
void pixelColor(const cv::Mat& img, int u, int v, std::uint8_t& r, std::uint8_t& g,
                std::uint8_t& b) {
  const uint8_t* px = img.ptr<uint8_t>(v) + static_cast<std::size_t>(u) * img.channels();
  if (img.channels() == 1) {
    r = g = b = px[0];
  } else {
    b = px[0];
    g = px[1];
    r = px[2];
  }
}

// ---------------------------------------------------------------------------------------------
// CObservation3DRangeScan

// Colours the points of the range scan from its intensity image: directly when the depth and
// intensity cameras coincide and the images have the same size, else by projecting each point
// (in the depth sensor frame) into the intensity camera, like MRPT's unprojectInto. Points that
// fall outside the image stay white (MRPT's choice). Set up once per scan (allocating the
// cloud's colour), then paint() per point, from any thread.
class RangeScanColour {
 public:
  RangeScanColour(const mrpt::obs::CObservation3DRangeScan& o, bool enabled, core::PointCloud& c) {
    if (!enabled || !o.hasIntensityImage) return;
    img_ = &o.intensityImage.asCvMatRef();
    if (!detail::usableImage(*img_)) {
      img_ = nullptr;
      return;
    }
    allocateColor(c);
    w_ = static_cast<int>(o.rangeImage.cols());
    const int h = static_cast<int>(o.rangeImage.rows());
    direct_ = o.doDepthAndIntensityCamerasCoincide() && img_->cols == w_ && img_->rows == h;
    const auto& cam = o.cameraParamsIntensity;
    // The intensity calibration may be given for another resolution than the stored image.
    const double sx = cam.ncols > 0 ? static_cast<double>(img_->cols) / cam.ncols : 1.0;
    const double sy = cam.nrows > 0 ? static_cast<double>(img_->rows) / cam.nrows : 1.0;
    fx_ = static_cast<float>(cam.fx() * sx), fy_ = static_cast<float>(cam.fy() * sy);
    cx_ = static_cast<float>(cam.cx() * sx), cy_ = static_cast<float>(cam.cy() * sy);
    intensity_from_depth_ = Transform(toIsometry(o.relativePoseIntensityWRTDepth).inverse());
  }

  bool enabled() const { return img_ != nullptr; }
  // Colours point pix (p_sensor: in the depth sensor frame).
  void paint(const Eigen::Vector3f& p_sensor, int pix, core::PointCloud& c) const {
    if (img_ == nullptr) return;
    if (direct_) {
      pixelColor(*img_, pix % w_, pix / w_, c.r[pix], c.g[pix], c.b[pix]);
      return;
    }
    const Eigen::Vector3f q = intensity_from_depth_(p_sensor);
    if (!(q.z() > 0.f)) return;
    // Compared as floats before any conversion: a damaged calibration gives NaN or huge values.
    const float u = std::round(cx_ + fx_ * q.x() / q.z());
    const float v = std::round(cy_ + fy_ * q.y() / q.z());
    if (!(u >= 0.f && v >= 0.f && u < img_->cols && v < img_->rows)) return;
    pixelColor(*img_, static_cast<int>(u), static_cast<int>(v), c.r[pix], c.g[pix], c.b[pix]);
  }

 private:
  const cv::Mat* img_ = nullptr;
  bool direct_ = false;
  int w_ = 0;
  float fx_ = 0, fy_ = 0, cx_ = 0, cy_ = 0;
  Transform intensity_from_depth_{Eigen::Isometry3d::Identity()};
};

void convertRangeScan(const mrpt::obs::CObservation3DRangeScan& o, const SourceParams& params,
                      ObservationCloud& out) {
  try {
    o.load();  // externally stored range image, points, intensity image
    if (o.hasIntensityImage && params.color_enabled) o.intensityImage.forceLoad();
  } catch (const std::exception& e) {
    out.skipped_reason = "CObservation3DRangeScan: cannot load its externally stored data (" +
                         detail::condenseMessage(e.what()) + ")";
    return;
  }
  const Transform robot_from_sensor(out.sensor_pose_on_robot);
  core::PointCloud& c = out.cloud_in_robot;
  c.sensor_origin = out.sensor_pose_on_robot.translation().cast<float>();

  const int w = static_cast<int>(o.rangeImage.cols());
  const int h = static_cast<int>(o.rangeImage.rows());
  if (o.hasRangeImage && w > 0 && h > 0) {
    if (static_cast<int>(o.cameraParams.ncols) != w ||
        static_cast<int>(o.cameraParams.nrows) != h) {
      out.skipped_reason = "CObservation3DRangeScan: the depth camera parameters are for " +
                           std::to_string(o.cameraParams.ncols) + "x" +
                           std::to_string(o.cameraParams.nrows) + " but the range image is " +
                           std::to_string(w) + "x" + std::to_string(h);
      return;
    }
    if (!(o.cameraParams.fx() > 0) || !(o.cameraParams.fy() > 0)) {
      out.skipped_reason = "CObservation3DRangeScan: the depth camera has no focal length";
      return;
    }
    // MRPT's unit ray (or unit-depth ray when range_is_depth) of every pixel, in the sensor
    // frame, with the lens distortion undone: the same numbers unprojectInto() uses.
    const auto& lut = o.get_unproj_lut();
    c.resizeOrganizedUnfilled(static_cast<std::size_t>(w), static_cast<std::size_t>(h));
    const RangeScanColour colour(o, params.color_enabled, c);
    // Rows in parallel, in the static shares of the frame stages after (each pixel is its own):
    // every point written, NaN where there is no return (no fill of the cloud first).
#pragma omp parallel for schedule(static)
    for (int v = 0; v < h; ++v) {
      rangeRow(&o.rangeImage(v, 0), o.rangeUnits, &lut.Kxs[v * w], &lut.Kys[v * w],
               &lut.Kzs[v * w], robot_from_sensor, w, &c.x[v * w], &c.y[v * w], &c.z[v * w]);
      if (!colour.enabled()) continue;
      for (int u = 0; u < w; ++u) {
        const std::uint16_t raw = o.rangeImage.coeff(v, u);
        if (raw == 0) continue;  // no return
        const int pix = v * w + u;
        const float range = static_cast<float>(raw) * o.rangeUnits;
        colour.paint(Eigen::Vector3f(lut.Kxs[pix] * range, lut.Kys[pix] * range,
                                     lut.Kzs[pix] * range),
                     pix, c);
      }
    }
    return;
  }
  if (o.hasPoints3D && !o.points3D_x.empty()) {
    const std::size_t n = o.points3D_x.size();
    if (o.points3D_y.size() != n || o.points3D_z.size() != n) {
      out.skipped_reason = "CObservation3DRangeScan: points3D_x/y/z differ in length";
      return;
    }
    c.x.resize(n);
    c.y.resize(n);
    c.z.resize(n);
    c.width = n;
    c.height = 1;
    for (std::size_t i = 0; i < n; ++i) {
      setPoint(c, i, robot_from_sensor({o.points3D_x[i], o.points3D_y[i], o.points3D_z[i]}));
    }
    return;
  }
  out.skipped_reason = "CObservation3DRangeScan has neither a range image nor 3D points";
}

// ---------------------------------------------------------------------------------------------
// CObservationPointCloud

void convertPointCloud(const mrpt::obs::CObservationPointCloud& o, const SourceParams& params,
                       ObservationCloud& out) {
  try {
    o.load();
  } catch (const std::exception& e) {
    out.skipped_reason = "CObservationPointCloud: cannot load its externally stored points (" +
                         detail::condenseMessage(e.what()) + ")";
    return;
  }
  if (!o.pointcloud) {
    out.skipped_reason = "CObservationPointCloud holds no point map";
    return;
  }
  const auto& map = *o.pointcloud;
  const auto& xs = map.getPointsBufferRef_x();
  const auto& ys = map.getPointsBufferRef_y();
  const auto& zs = map.getPointsBufferRef_z();
  const std::size_t n = xs.size();
  const Transform robot_from_sensor(out.sensor_pose_on_robot);
  core::PointCloud& c = out.cloud_in_robot;
  c.x.resize(n);
  c.y.resize(n);
  c.z.resize(n);
  c.width = n;
  c.height = 1;
  c.sensor_origin = out.sensor_pose_on_robot.translation().cast<float>();
  for (std::size_t i = 0; i < n; ++i) setPoint(c, i, robot_from_sensor({xs[i], ys[i], zs[i]}));
  if (!params.color_enabled || n == 0) return;
  // MRPT's colours and intensities are in [0, 1]; a NaN (a damaged or unset value) is black.
  const auto toU8 = [](float f) {
    return f > 0.f ? static_cast<std::uint8_t>(std::min(f, 1.f) * 255.f + 0.5f) : std::uint8_t{0};
  };
  if (const auto* col = dynamic_cast<const mrpt::maps::CColouredPointsMap*>(&map)) {
    allocateColor(c);
    for (std::size_t i = 0; i < n; ++i) {
      float r, g, b;
      col->getPointColor(i, r, g, b);
      c.r[i] = toU8(r);
      c.g[i] = toU8(g);
      c.b[i] = toU8(b);
    }
  } else if (const auto* xyzi = dynamic_cast<const mrpt::maps::CPointsMapXYZI*>(&map)) {
    allocateColor(c);
    for (std::size_t i = 0; i < n; ++i) {
      c.r[i] = c.g[i] = c.b[i] = toU8(xyzi->getPointIntensity(i));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// LiDARs

// Default calibration for a model name as MRPT spells it in observations ("VLP-16", "HDL-32E",
// "VLP16", ...); empty when unknown.
const mrpt::obs::VelodyneCalibration* defaultVelodyneCalibration(std::string model) {
  model.erase(std::remove_if(model.begin(), model.end(),
                             [](unsigned char ch) { return ch == '-' || ch == '_' || ch == ' '; }),
              model.end());
  std::transform(model.begin(), model.end(), model.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::toupper(ch)); });
  std::string name;
  if (model.rfind("VLP16", 0) == 0) name = "VLP16";
  if (model.rfind("HDL32", 0) == 0) name = "HDL32";
  if (model.rfind("HDL64", 0) == 0) name = "HDL64";
  if (name.empty()) return nullptr;
  const auto& calib = mrpt::obs::VelodyneCalibration::LoadDefaultCalibration(name);
  return calib.empty() ? nullptr : &calib;
}

struct VelodyneSink : mrpt::obs::CObservationVelodyneScan::PointCloudStorageWrapper {
  core::PointCloud& cloud;
  Transform robot_from_sensor;
  bool color;
  VelodyneSink(core::PointCloud& c, const Eigen::Isometry3d& pose, bool with_color)
      : cloud(c), robot_from_sensor(pose), color(with_color) {}
  void reserve(std::size_t n) override {
    cloud.reserve(n);
    if (color) {
      cloud.r.reserve(n);
      cloud.g.reserve(n);
      cloud.b.reserve(n);
    }
  }
  void add_point(float x, float y, float z, uint8_t intensity, const mrpt::system::TTimeStamp&,
                 const float, uint16_t) override {
    const Eigen::Vector3f p = robot_from_sensor({x, y, z});
    if (color) {
      cloud.push_back(p.x(), p.y(), p.z(), intensity, intensity, intensity);
    } else {
      cloud.push_back(p.x(), p.y(), p.z());
    }
  }
};

void convertVelodyne(const mrpt::obs::CObservationVelodyneScan& o, const SourceParams& params,
                     ObservationCloud& out) {
  if (o.scan_packets.empty()) {
    out.skipped_reason = "CObservationVelodyneScan holds no packets";
    return;
  }
  mrpt::obs::CObservationVelodyneScan scan = o;  // generatePointCloud() is not const
  if (scan.calibration.empty()) {
    // The factory byte of the raw packets names the model.
    const int model = scan.scan_packets.front().velodyne_model_ID;
    const auto* calib = defaultVelodyneCalibration(model == 0x22   ? "VLP16"
                                                   : model == 0x21 ? "HDL32"
                                                                   : "");
    if (!calib) {
      out.skipped_reason = "CObservationVelodyneScan without calibration, and its model byte " +
                           std::to_string(model) + " has no default calibration";
      return;
    }
    scan.calibration = *calib;
  }
  mrpt::obs::CObservationVelodyneScan::TGeneratePointCloudParameters gp;
  gp.minDistance = static_cast<float>(params.lidar_min_range_m);
  gp.maxDistance = static_cast<float>(params.lidar_max_range_m);
  core::PointCloud& c = out.cloud_in_robot;
  VelodyneSink sink(c, out.sensor_pose_on_robot, params.color_enabled);
  scan.generatePointCloud(sink, gp);
  c.width = c.size();
  c.height = 1;
  c.sensor_origin = out.sensor_pose_on_robot.translation().cast<float>();
}

void convertRotatingScan(const mrpt::obs::CObservationRotatingScan& o, const SourceParams& params,
                         ObservationCloud& out) {
  const int rows = static_cast<int>(o.rangeImage.rows());
  const int cols = static_cast<int>(o.rangeImage.cols());
  if (rows == 0 || cols == 0) {
    out.skipped_reason = "CObservationRotatingScan with an empty range image";
    return;
  }
  if (rows == 1) {
    out.skipped_reason =
        "CObservationRotatingScan with a single ring has no 3D points (a planar scan)";
    return;
  }
  const auto* calib = defaultVelodyneCalibration(o.lidarModel);
  if (!calib || calib->laser_corrections.size() != static_cast<std::size_t>(rows)) {
    out.skipped_reason = "CObservationRotatingScan of lidar model '" + o.lidarModel + "' with " +
                         std::to_string(rows) +
                         " rings: MRPT 2.5 stores no per-ring elevation and no default "
                         "calibration (VLP16, HDL32, HDL64) matches";
    return;
  }
  const Transform robot_from_sensor(out.sensor_pose_on_robot);
  core::PointCloud& c = out.cloud_in_robot;
  c.resizeOrganized(static_cast<std::size_t>(cols), static_cast<std::size_t>(rows));
  c.sensor_origin = out.sensor_pose_on_robot.translation().cast<float>();
  const bool color =
      params.color_enabled && o.intensityImage.rows() == rows && o.intensityImage.cols() == cols;
  if (color) allocateColor(c);
  const double min_range = std::max(params.lidar_min_range_m, o.minRange);
  const double max_range = std::min(params.lidar_max_range_m, o.maxRange);
  // Azimuth of the first and the last column; positive is counter-clockwise (about +z).
  const double step = cols > 1 ? o.azimuthSpan / (cols - 1) : 0.0;
  for (int r = 0; r < rows; ++r) {
    const double el = calib->laser_corrections[r].verticalCorrection * core::kDegToRad;
    const double cos_el = std::cos(el), sin_el = std::sin(el);
    for (int col = 0; col < cols; ++col) {
      const std::uint16_t raw = o.rangeImage.coeff(r, col);
      if (raw == 0) continue;
      const double range = raw * o.rangeResolution;
      if (range < min_range || range > max_range) continue;
      const double az = o.startAzimuth + step * col;
      const Eigen::Vector3f p_sensor(static_cast<float>(range * cos_el * std::cos(az)),
                                     static_cast<float>(range * cos_el * std::sin(az)),
                                     static_cast<float>(range * sin_el));
      const std::size_t i = static_cast<std::size_t>(r) * cols + col;
      setPoint(c, i, robot_from_sensor(p_sensor));
      if (color) c.r[i] = c.g[i] = c.b[i] = o.intensityImage.coeff(r, col);
    }
  }
}

}  // namespace

ObservationCloud toCloud(const mrpt::obs::CObservation& obs, const SourceParams& params) {
  ObservationCloud out;
  toCloud(obs, params, out);
  return out;
}

void toCloud(const mrpt::obs::CObservation& obs, const SourceParams& params,
             ObservationCloud& out) {
  params.validate();
  // Emptied, its buffers kept: a sensor loop's range images convert without allocating (and a
  // skipped observation, below, leaves them for the next frame too).
  core::PointCloud& c = out.cloud_in_robot;
  const auto empty = [&c] {
    c.x.clear(), c.y.clear(), c.z.clear(), c.r.clear(), c.g.clear(), c.b.clear();
    c.width = 0, c.height = 1;
    c.sensor_origin.setZero();
  };
  empty();
  out.skipped_reason.clear();
  out.source_class = detail::shortClassName(obs);
  out.sensor_pose_on_robot = sensorPoseOnRobot(obs);
  if (!out.sensor_pose_on_robot.matrix().allFinite()) {  // (a corrupt observation: NaN, Inf)
    out.skipped_reason = out.source_class + ": its sensor pose on the robot is not finite";
    empty();
    return;
  }
  if (const auto* o = dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(&obs)) {
    convertRangeScan(*o, params, out);
  } else if (const auto* pc = dynamic_cast<const mrpt::obs::CObservationPointCloud*>(&obs)) {
    convertPointCloud(*pc, params, out);
  } else if (const auto* vel = dynamic_cast<const mrpt::obs::CObservationVelodyneScan*>(&obs)) {
    convertVelodyne(*vel, params, out);
  } else if (const auto* rot = dynamic_cast<const mrpt::obs::CObservationRotatingScan*>(&obs)) {
    convertRotatingScan(*rot, params, out);
  } else if (const auto* st = dynamic_cast<const mrpt::obs::CObservationStereoImages*>(&obs)) {
    detail::convertStereo(*st, params, out);
  } else if (dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(&obs)) {
    out.skipped_reason = "CObservation2DRangeScan has no 3D points (a planar laser scan)";
  } else {
    out.skipped_reason = out.source_class + " carries no 3D points";
  }
  if (!out.ok()) empty();
}

}  // namespace upd::mrpt_bridge
