#include "upd/mrpt/simulated_run.h"

#include "upd/core/terrain.h"
#include "upd/io/atomic_file.h"

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/datetime.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <queue>
#include <random>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

namespace upd::mrptbridge {

namespace fs = std::filesystem;

void SimulationParams::validate() const {
  const char* s = "SimulationParams";
  requireParam(robot_length_m > 0, s, "robot_length_m", robot_length_m, "must be > 0");
  requireParam(robot_width_m > 0, s, "robot_width_m", robot_width_m, "must be > 0");
  requireParam(wheel_diameter_m > 0, s, "wheel_diameter_m", wheel_diameter_m, "must be > 0");
  requireParam(camera_height_m > 0, s, "camera_height_m", camera_height_m, "must be > 0");
  requireParam(camera_pitch_rad >= 0 && camera_pitch_rad < 0.5 * M_PI, s, "camera_pitch_deg",
               camera_pitch_rad * kRadToDeg, "must be in [0, 90)");
  requireParam(speed_mps > 0, s, "speed_mps", speed_mps, "must be > 0");
  requireParam(frame_spacing_m > 0, s, "frame_spacing_m", frame_spacing_m, "must be > 0");
  requireParam(clearance_m >= 0, s, "clearance_m", clearance_m, "must be >= 0");
  requireParam(odometry_sigma_ratio >= 0, s, "odometry_sigma_ratio", odometry_sigma_ratio,
               "must be >= 0");
  requireParam(truth_cell_m > 0, s, "truth_cell_m", truth_cell_m, "must be > 0");
  requireParam(seed >= 0, s, "seed", seed, "must be >= 0");
}

Eigen::Matrix3d opticalToMrptSensor() {
  Eigen::Matrix3d m;
  m << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return m;
}

Eigen::Isometry3d kinectPoseOnRobot(const SimulationParams& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.camera_forward_m, 0, p.camera_height_m);
  // MRPT pitch > 0 turns +x towards -z: the camera looks down.
  t.linear() = Eigen::AngleAxisd(p.camera_pitch_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return t;
}

namespace {

// The route planner's grid: a cell is free when no non-traversable (or unknown) truth lies
// within the clearance, so the robot's body never touches an obstacle.
struct PlanGrid {
  double cell = 0.1;
  Eigen::Vector2d origin;
  int w = 0, h = 0;
  std::vector<float> clearance_m;  // distance to the nearest blocked truth cell
  bool inside(int i, int j) const { return i >= 0 && j >= 0 && i < w && j < h; }
  Eigen::Vector2d centre(int i, int j) const {
    return origin + Eigen::Vector2d((i + 0.5) * cell, (j + 0.5) * cell);
  }
};

PlanGrid makePlanGrid(const Terrain& t) {
  PlanGrid g;
  g.origin = t.minXY();
  g.w = static_cast<int>(std::ceil((t.maxXY().x() - t.minXY().x()) / g.cell));
  g.h = static_cast<int>(std::ceil((t.maxXY().y() - t.minXY().y()) / g.cell));
  const float inf = std::numeric_limits<float>::infinity();
  g.clearance_m.assign(static_cast<std::size_t>(g.w) * g.h, inf);
  // Multi-source Dijkstra (8-connected) from the blocked cells and the world's border.
  using Item = std::pair<float, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> q;
  for (int j = 0; j < g.h; ++j) {
    for (int i = 0; i < g.w; ++i) {
      const Eigen::Vector2d c = g.centre(i, j);
      const bool border = i == 0 || j == 0 || i == g.w - 1 || j == g.h - 1;
      if (border || t.truthAt(c.x(), c.y()) != Label::Traversable) {
        g.clearance_m[j * g.w + i] = 0;
        q.emplace(0.f, j * g.w + i);
      }
    }
  }
  while (!q.empty()) {
    const auto [d, idx] = q.top();
    q.pop();
    if (d > g.clearance_m[idx]) continue;
    const int i = idx % g.w, j = idx / g.w;
    for (int dj = -1; dj <= 1; ++dj) {
      for (int di = -1; di <= 1; ++di) {
        if ((!di && !dj) || !g.inside(i + di, j + dj)) continue;
        const float nd = d + static_cast<float>(g.cell * std::hypot(di, dj));
        const int n = (j + dj) * g.w + i + di;
        if (nd < g.clearance_m[n]) {
          g.clearance_m[n] = nd;
          q.emplace(nd, n);
        }
      }
    }
  }
  return g;
}

// A* between two world points over cells with clearance >= clearance_m.
std::vector<Eigen::Vector2d> astar(const PlanGrid& g, const Eigen::Vector2d& from,
                                   const Eigen::Vector2d& to, double clearance_m,
                                   const std::string& world) {
  auto cellOf = [&](const Eigen::Vector2d& p) {
    return std::make_pair(static_cast<int>(std::floor((p.x() - g.origin.x()) / g.cell)),
                          static_cast<int>(std::floor((p.y() - g.origin.y()) / g.cell)));
  };
  auto free = [&](int i, int j) { return g.inside(i, j) && g.clearance_m[j * g.w + i] >= clearance_m; };
  const auto [si, sj] = cellOf(from);
  const auto [gi, gj] = cellOf(to);
  if (!free(si, sj)) {
    throw std::invalid_argument("world '" + world + "': the start is closer than " +
                                std::to_string(clearance_m) + " m to non-traversable ground");
  }
  if (!free(gi, gj)) {
    throw std::invalid_argument("world '" + world + "': the goal is closer than " +
                                std::to_string(clearance_m) + " m to non-traversable ground");
  }
  const int n = g.w * g.h;
  std::vector<float> cost(n, std::numeric_limits<float>::infinity());
  std::vector<int> parent(n, -1);
  using Item = std::pair<float, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  const int start = sj * g.w + si, goal = gj * g.w + gi;
  auto heuristic = [&](int idx) {
    return static_cast<float>(g.cell * std::hypot(idx % g.w - gi, idx / g.w - gj));
  };
  cost[start] = 0;
  open.emplace(heuristic(start), start);
  while (!open.empty()) {
    const auto [f, idx] = open.top();
    open.pop();
    if (idx == goal) break;
    if (f - heuristic(idx) > cost[idx] + 1e-4f) continue;
    const int i = idx % g.w, j = idx / g.w;
    for (int dj = -1; dj <= 1; ++dj) {
      for (int di = -1; di <= 1; ++di) {
        if ((!di && !dj) || !free(i + di, j + dj)) continue;
        const int nb = (j + dj) * g.w + i + di;
        const float c = cost[idx] + static_cast<float>(g.cell * std::hypot(di, dj));
        if (c < cost[nb]) {
          cost[nb] = c;
          parent[nb] = idx;
          open.emplace(c + heuristic(nb), nb);
        }
      }
    }
  }
  if (parent[goal] < 0 && goal != start) {
    throw std::invalid_argument("world '" + world + "': the goal cannot be reached with " +
                                std::to_string(clearance_m) + " m clearance");
  }
  std::vector<Eigen::Vector2d> cells;
  for (int idx = goal; idx >= 0; idx = parent[idx]) cells.push_back(g.centre(idx % g.w, idx / g.w));
  std::reverse(cells.begin(), cells.end());
  cells.front() = from;
  cells.back() = to;
  // Shortcut: keep a waypoint only where the straight line to the next one would leave the
  // free cells, so the robot drives straight segments instead of grid zig-zags.
  auto lineFree = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const int steps = static_cast<int>(std::ceil((b - a).norm() / (0.25 * g.cell))) + 1;
    for (int s = 0; s <= steps; ++s) {
      const auto [i, j] = cellOf(a + (b - a) * (double(s) / steps));
      if (!free(i, j)) return false;
    }
    return true;
  };
  std::vector<Eigen::Vector2d> path{cells.front()};
  std::size_t k = 0;
  while (k + 1 < cells.size()) {
    std::size_t far = k + 1;
    for (std::size_t m = cells.size() - 1; m > k + 1; --m) {
      if (lineFree(cells[k], cells[m])) {
        far = m;
        break;
      }
    }
    path.push_back(cells[far]);
    k = far;
  }
  return path;
}

// The robot's body resting on the terrain at (x, y, yaw): height and tilt from its four wheels.
Eigen::Isometry3d restOnTerrain(const Terrain& t, const SimulationParams& p, double x, double y,
                                double yaw) {
  const double half_base = 0.5 * (p.robot_length_m - p.wheel_diameter_m);
  const double half_track = 0.5 * p.robot_width_m;
  const Eigen::Vector2d fwd(std::cos(yaw), std::sin(yaw)), left(-fwd.y(), fwd.x());
  const Eigen::Vector2d c(x, y);
  auto h = [&](double f, double l) {
    const Eigen::Vector2d q = c + f * half_base * fwd + l * half_track * left;
    return t.heightAt(q.x(), q.y());
  };
  const double fl = h(1, 1), fr = h(1, -1), rl = h(-1, 1), rr = h(-1, -1);
  const double pitch = -std::atan2(0.5 * (fl + fr - rl - rr), 2 * half_base);  // nose up < 0
  const double roll = std::atan2(0.5 * (fl + rl - fr - rr), 2 * half_track);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, y, 0.25 * (fl + fr + rl + rr));
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  return pose;
}

double wrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

void writeAtomicallyWith(const std::string& path, const std::function<void(const std::string&)>& w) {
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  if (!fs::is_directory(dir)) {
    throw std::runtime_error("cannot write " + path + ": directory " + dir.string() +
                             " does not exist");
  }
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  try {
    w(tmp);
    fs::rename(tmp, target);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

std::string stemOf(const std::string& rawlog_path) {
  fs::path p(rawlog_path);
  return (p.parent_path() / p.stem()).string();
}

}  // namespace

std::string groundTruthPosesPath(const std::string& rawlog_path) {
  return stemOf(rawlog_path) + ".gt.tum";
}
std::string truthMapPath(const std::string& rawlog_path) {
  return stemOf(rawlog_path) + ".truth.yaml";
}

std::vector<RoutePose> planRoute(const WorldSpec& world, const SimulationParams& p) {
  p.validate();
  const Terrain& t = world.terrain;
  const PlanGrid grid = makePlanGrid(t);
  const Eigen::Vector2d start = world.start_xy_yaw.head<2>();
  std::vector<Eigen::Vector2d> way = astar(grid, start, world.goal_xy, p.clearance_m,
                                           world.description);
  if (p.return_to_start) {
    const auto back = astar(grid, world.goal_xy, start, p.clearance_m, world.description);
    way.insert(way.end(), back.begin() + 1, back.end());
  }
  // Sample the polyline every frame_spacing_m; turn in place (15 deg steps) at each corner so
  // the camera never jumps.
  std::vector<RoutePose> route;
  double yaw = world.start_xy_yaw.z(), t_s = 0;
  const double turn_step = 15.0 * kDegToRad;
  const double turn_rate = p.speed_mps / (0.5 * p.robot_width_m);  // wheels at speed_mps
  auto emit = [&](const Eigen::Vector2d& xy) {
    route.push_back({t_s, restOnTerrain(t, p, xy.x(), xy.y(), yaw), yaw});
  };
  emit(way.front());
  for (std::size_t k = 0; k + 1 < way.size(); ++k) {
    const Eigen::Vector2d a = way[k], b = way[k + 1];
    const double len = (b - a).norm();
    if (len < 1e-9) continue;
    const double heading = std::atan2(b.y() - a.y(), b.x() - a.x());
    double dyaw = wrapAngle(heading - yaw);
    while (std::abs(dyaw) > 1e-9) {
      const double step = std::clamp(dyaw, -turn_step, turn_step);
      yaw = wrapAngle(yaw + step);
      dyaw -= step;
      t_s += std::abs(step) / turn_rate;
      emit(a);
    }
    const int n = std::max(1, static_cast<int>(std::round(len / p.frame_spacing_m)));
    for (int s = 1; s <= n; ++s) {
      t_s += len / n / p.speed_mps;
      emit(a + (b - a) * (double(s) / n));
    }
  }
  return route;
}

void writeTruthMap(const Terrain& terrain, double cell_m, const std::string& yaml_path) {
  const Eigen::Vector2d lo = terrain.minXY();
  const int w = static_cast<int>(std::ceil((terrain.maxXY().x() - lo.x()) / cell_m));
  const int h = static_cast<int>(std::ceil((terrain.maxXY().y() - lo.y()) / cell_m));
  std::vector<std::uint8_t> img(static_cast<std::size_t>(w) * h);
  for (int row = 0; row < h; ++row) {
    for (int i = 0; i < w; ++i) {
      const int j = h - 1 - row;  // row 0 is the top (max y)
      const Label l = terrain.truthAt(lo.x() + (i + 0.5) * cell_m, lo.y() + (j + 0.5) * cell_m);
      img[static_cast<std::size_t>(row) * w + i] =
          l == Label::NonTraversable ? 0 : l == Label::Traversable ? 254 : 205;
    }
  }
  const fs::path yaml(yaml_path);
  const std::string pgm = (yaml.parent_path() / yaml.stem()).string() + ".pgm";
  io::writeFileAtomically(pgm, [&](std::ostream& os) {
    os << "P5\n" << w << " " << h << "\n255\n";
    os.write(reinterpret_cast<const char*>(img.data()), static_cast<std::streamsize>(img.size()));
  });
  io::writeFileAtomically(yaml_path, [&](std::ostream& os) {
    os << std::setprecision(10) << "image: " << fs::path(pgm).filename().string()
       << "\nresolution: " << cell_m << "\norigin: [" << lo.x() << ", " << lo.y()
       << ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n";
  });
}

int TruthGrid::labelAt(double x, double y) const {
  const int i = static_cast<int>(std::floor((x - origin_xy.x()) / resolution_m));
  const int j = static_cast<int>(std::floor((y - origin_xy.y()) / resolution_m));
  if (i < 0 || j < 0 || i >= width || j >= height) return 2;
  const std::uint8_t v = pgm[static_cast<std::size_t>(height - 1 - j) * width + i];
  return v < 100 ? 1 : v > 250 ? 0 : 2;
}

TruthGrid readTruthMap(const std::string& yaml_path) {
  std::ifstream in(yaml_path);
  if (!in) throw std::runtime_error("ground-truth map " + yaml_path + ": cannot be opened");
  TruthGrid g;
  std::string line, image;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(0, colon);
    std::string value = line.substr(colon + 1);
    if (key == "image") {
      std::istringstream(value) >> image;
    } else if (key == "resolution") {
      g.resolution_m = std::stod(value);
    } else if (key == "origin") {
      std::replace_if(value.begin(), value.end(), [](char c) { return c == '[' || c == ']' || c == ','; }, ' ');
      std::istringstream(value) >> g.origin_xy.x() >> g.origin_xy.y();
    }
  }
  if (image.empty()) throw std::runtime_error("ground-truth map " + yaml_path + ": no image key");
  const fs::path pgm_path = fs::path(yaml_path).parent_path() / image;
  std::ifstream pgm(pgm_path, std::ios::binary);
  std::string magic;
  int maxval = 0;
  if (!(pgm >> magic >> g.width >> g.height >> maxval) || magic != "P5" || maxval != 255) {
    throw std::runtime_error("ground-truth map " + pgm_path.string() + ": not an 8-bit P5 PGM");
  }
  pgm.get();
  g.pgm.resize(static_cast<std::size_t>(g.width) * g.height);
  if (!pgm.read(reinterpret_cast<char*>(g.pgm.data()), static_cast<std::streamsize>(g.pgm.size()))) {
    throw std::runtime_error("ground-truth map " + pgm_path.string() + ": truncated");
  }
  return g;
}

SimulationSummary simulateRun(const WorldSpec& world, const SimulationParams& p,
                              const std::string& rawlog_path, int max_frames) {
  p.validate();
  std::vector<RoutePose> route = planRoute(world, p);
  if (max_frames > 0 && route.size() > static_cast<std::size_t>(max_frames)) {
    route.resize(static_cast<std::size_t>(max_frames));
  }
  const CameraIntrinsics K;  // Kinect: 640 x 480, fx = fy = 525
  const DepthNoise noise;    // sigma = 1.2e-3 z^2, 0.4 .. 8 m, millimetre steps
  const Eigen::Isometry3d sensor_on_robot = kinectPoseOnRobot(p);
  Eigen::Isometry3d optical_in_sensor = Eigen::Isometry3d::Identity();
  optical_in_sensor.linear() = opticalToMrptSensor();
  const double t0 = 1.7e9;  // timestamps in seconds since the epoch, as a real recording

  std::mt19937 rng(static_cast<std::uint32_t>(p.seed));
  std::normal_distribution<double> gauss(0.0, 1.0);
  mrpt::obs::CActionRobotMovement2D::TMotionModelOptions motion;
  motion.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;

  SimulationSummary summary;
  summary.rawlog_path = rawlog_path;
  summary.poses_path = groundTruthPosesPath(rawlog_path);
  summary.truth_yaml_path = truthMapPath(rawlog_path);

  writeAtomicallyWith(rawlog_path, [&](const std::string& tmp) {
    mrpt::io::CFileGZOutputStream out;
    if (!out.open(tmp, 1)) throw std::runtime_error("cannot write " + tmp);
    auto arch = mrpt::serialization::archiveFrom(out);
    for (std::size_t k = 0; k < route.size(); ++k) {
      const RoutePose& rp = route[k];
      const auto stamp = mrpt::Clock::fromDouble(t0 + rp.t_s);
      // Odometry: the true planar increment, with noise proportional to the distance and a
      // heading drift, as wheel odometry on a skid-steer rover.
      mrpt::obs::CActionCollection actions;
      if (k > 0) {
        const mrpt::poses::CPose2D a(route[k - 1].pose_world_robot.translation().x(),
                                     route[k - 1].pose_world_robot.translation().y(),
                                     route[k - 1].yaw_rad);
        const mrpt::poses::CPose2D b(rp.pose_world_robot.translation().x(),
                                     rp.pose_world_robot.translation().y(), rp.yaw_rad);
        mrpt::poses::CPose2D inc = b - a;
        const double dist = std::hypot(inc.x(), inc.y());
        const double scale = 1.0 + p.odometry_sigma_ratio * gauss(rng);
        inc.x(inc.x() * scale);
        inc.y(inc.y() * scale);
        inc.phi(inc.phi() + p.odometry_yaw_bias_rad_per_m * dist +
                0.2 * p.odometry_sigma_ratio * dist * gauss(rng));
        mrpt::obs::CActionRobotMovement2D act;
        act.computeFromOdometry(inc, motion);
        act.timestamp = stamp;
        actions.insert(act);
      }
      arch << actions;

      const Eigen::Isometry3d pose_world_camera =
          rp.pose_world_robot * sensor_on_robot * optical_in_sensor;
      const DepthImage depth = renderDepth(world.terrain, pose_world_camera, K, noise,
                                           static_cast<std::uint32_t>(p.seed * 100003 + k));
      auto obs = mrpt::obs::CObservation3DRangeScan::Create();
      obs->sensorLabel = "KINECT";
      obs->timestamp = stamp;
      obs->hasRangeImage = true;
      obs->range_is_depth = true;
      obs->rangeUnits = 0.001f;
      obs->maxRange = static_cast<float>(noise.max_range_m);
      obs->rangeImage_setSize(K.height, K.width);
      for (int v = 0; v < K.height; ++v) {
        for (int u = 0; u < K.width; ++u) {
          const float d = depth.at(u, v);
          obs->rangeImage(v, u) =
              d > 0.f && std::isfinite(d) ? static_cast<std::uint16_t>(std::lround(d * 1000.f)) : 0;
        }
      }
      obs->cameraParams.ncols = K.width;
      obs->cameraParams.nrows = K.height;
      obs->cameraParams.setIntrinsicParamsFromValues(K.fx, K.fy, K.cx, K.cy);
      obs->cameraParamsIntensity = obs->cameraParams;
      const Eigen::Vector3d ypr = sensor_on_robot.linear().eulerAngles(2, 1, 0);
      obs->sensorPose = mrpt::poses::CPose3D(sensor_on_robot.translation().x(),
                                             sensor_on_robot.translation().y(),
                                             sensor_on_robot.translation().z(), ypr[0], ypr[1],
                                             ypr[2]);
      mrpt::obs::CSensoryFrame sf;
      sf.insert(obs);
      arch << sf;
    }
  });

  io::writeFileAtomically(summary.poses_path, [&](std::ostream& os) {
    os << "# ground-truth poses of the robot (TUM: t x y z qx qy qz qw), world frame z up\n"
       << std::fixed << std::setprecision(6);
    for (const RoutePose& rp : route) {
      const Eigen::Quaterniond q(rp.pose_world_robot.linear());
      const Eigen::Vector3d t = rp.pose_world_robot.translation();
      os << t0 + rp.t_s << " " << t.x() << " " << t.y() << " " << t.z() << " " << q.x() << " "
         << q.y() << " " << q.z() << " " << q.w() << "\n";
    }
  });
  writeTruthMap(world.terrain, p.truth_cell_m, summary.truth_yaml_path);

  summary.frames = route.size();
  for (std::size_t k = 1; k < route.size(); ++k) {
    summary.path_length_m +=
        (route[k].pose_world_robot.translation() - route[k - 1].pose_world_robot.translation())
            .head<2>()
            .norm();
  }
  summary.duration_s = route.empty() ? 0 : route.back().t_s;
  return summary;
}

}  // namespace upd::mrptbridge
