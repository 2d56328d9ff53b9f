#include "upd/nav/nav_config.h"

#include "upd/mrpt_bridge/ini_params.h"
#include "upd/mrpt_bridge/robot_config.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <system_error>
#include <vector>

namespace fs = std::filesystem;

namespace upd::nav {

void LoopParams::validate() const {
  core::requireParam(std::isfinite(control_period_s) && control_period_s > 0 && control_period_s <= 2,
               "LoopParams", "control_period_s", control_period_s, "must be in (0, 2]");
  core::requireParam(std::isfinite(max_time_s) && max_time_s > 0, "LoopParams", "max_time_s", max_time_s,
               "must be > 0");
  core::requireParam(seed >= 0, "LoopParams", "seed", seed, "must be >= 0");
  core::requireParam(std::isfinite(truth_cell_m) && truth_cell_m > 0 && truth_cell_m <= 0.2, "LoopParams",
               "truth_cell_m", truth_cell_m, "must be in (0, 0.2]");
  core::requireParam(std::isfinite(clearance_search_m) && clearance_search_m > 0, "LoopParams",
               "clearance_search_m", clearance_search_m, "must be > 0");
}

void PerceptionParams::validate() const {
  core::requireParam(std::isfinite(upd_radius_m) && upd_radius_m >= 0, "PerceptionParams",
                     "upd_radius_m", upd_radius_m, "must be >= 0 (0: the robot config's)");
}

void NavConfig::validate() const {
  pipeline.validate();
  baseline.validate();
  grid.validate();
  fusion.validate();
  depth_noise.validate();
  body.validate();
  camera.validate();
  base.validate();
  obstacles.validate();
  negative.validate();
  step_edges.validate();
  route.validate();
  navigator.validate();
  recovery.validate();
  loop.validate();
  perception.validate();
  if (ptg_ini.empty()) {
    throw std::invalid_argument("NavigatorParams.ptg_ini is not set (the MRPT navigator's ini)");
  }
}

namespace {

// [NavigatorParams] string keys: paths relative to the file that holds them.
void readPath(mrpt_bridge::IniReader& ini, const char* key, std::string& out) {
  ini.markKnown("NavigatorParams", key);
  if (!ini.hasKey("NavigatorParams", key)) return;
  const std::string v = ini.rawValue("NavigatorParams", key);
  if (v.empty()) {
    out.clear();
    return;
  }
  fs::path p(v);
  if (p.is_relative()) p = fs::path(ini.path()).parent_path() / p;
  out = p.lexically_normal().string();
}

}  // namespace

NavConfig loadNavConfig(const std::string& robot_ini, const std::string& nav_ini) {
  NavConfig c;
  {
    mrpt_bridge::IniReader ini(robot_ini);
    // The sections the loop uses; the others are the `upd` commands' (see the header comment).
    mrpt_bridge::RobotConfigParts parts;
    parts.pipeline = &c.pipeline;
    parts.baseline = &c.baseline;
    parts.grid = &c.grid;
    parts.fusion = &c.fusion;
    mrpt_bridge::readRobotConfig(ini, parts);
  }
  {
    mrpt_bridge::IniReader ini(nav_ini);
    forEachNavSection(c,
                      [&](const char* name, const char*, auto& params) { ini.read(name, params); });
    readPath(ini, "ptg_ini", c.ptg_ini);
    readPath(ini, "ptg_cache_dir", c.ptg_cache_dir);
    ini.checkAllKeysKnown();
  }
  if (c.ptg_cache_dir.empty()) c.ptg_cache_dir = defaultPtgCacheDir();
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("config " + robot_ini + " + " + nav_ini + ": " + e.what());
  }
  return c;
}

namespace {

// The data directory beside an executable at <exe_dir>: <exe_dir>/../share/upd-nav (installed:
// <prefix>/bin/upd) and <exe_dir>/../../share/upd-nav (the build tree: build/apps/upd/upd).
std::vector<fs::path> dataDirsBeside(const fs::path& exe_dir) {
  return {(exe_dir / ".." / "share" / "upd-nav").lexically_normal(),
          (exe_dir / ".." / ".." / "share" / "upd-nav").lexically_normal()};
}

bool holdsConfig(const fs::path& dir) {
  std::error_code ec;
  return fs::is_directory(dir / "config", ec);
}

}  // namespace

std::string defaultDataDir() {
  if (const char* env = std::getenv("UPD_NAV_DATA_DIR"); env != nullptr && *env != '\0') {
    if (holdsConfig(env)) return env;
    throw std::runtime_error(std::string("UPD_NAV_DATA_DIR = ") + env +
                             " holds no config/ directory");
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) {
    throw std::runtime_error("cannot find UPD-Nav's data: /proc/self/exe is unreadable (" +
                             ec.message() + "); set UPD_NAV_DATA_DIR or pass the config files");
  }
  std::string searched;
  for (const fs::path& dir : dataDirsBeside(exe.parent_path())) {
    if (holdsConfig(dir)) return dir.string();
    searched += (searched.empty() ? "" : ", ") + (dir / "config").string();
  }
  throw std::runtime_error("cannot find UPD-Nav's config/ directory (looked in " + searched +
                           "): set UPD_NAV_DATA_DIR to the directory holding it, or pass the "
                           "config files");
}

std::string defaultConfigDir() {
  if (const char* env = std::getenv("UPD_CONFIG_DIR"); env != nullptr && *env != '\0') {
    return env;
  }
  return (fs::path(defaultDataDir()) / "config").string();
}

std::string defaultPtgCacheDir() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg != '\0') {
    return (fs::path(xdg) / "upd-nav" / "ptg").string();
  }
  if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0') {
    return (fs::path(home) / ".cache" / "upd-nav" / "ptg").string();
  }
  return (fs::temp_directory_path() / "upd-nav-ptg").string();
}

}  // namespace upd::nav
