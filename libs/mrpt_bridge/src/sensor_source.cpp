#include "upd/mrpt_bridge/sensor_source.h"

#include "mrpt_util.h"
#include "sensor_driver.h"
#include "upd/mrpt_bridge/module.h"
#include "upd/mrpt_bridge/stereo.h"

#include <mrpt/config/CConfigFile.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/poses/CPose3DQuat.h>

#include <filesystem>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <vector>

namespace fs = std::filesystem;

namespace upd::mrpt_bridge {

namespace detail {

SensorDriver::~SensorDriver() = default;

const SensorDrivers& sensorDrivers() {
#ifdef UPD_SENSOR_MODULE
  static const char here = 0;
  return moduleEntry<SensorDrivers>(UPD_SENSOR_MODULE, "upd_mrpt_sensor_drivers", &here);
#else
  return upd_mrpt_sensor_drivers;
#endif
}

}  // namespace detail

namespace {

// The file, read-only (CConfigFile would rewrite a file it modified: it never is here).
std::unique_ptr<mrpt::config::CConfigFile> openIni(const std::string& path) {
  if (!fs::is_regular_file(path)) throw std::runtime_error("sensor file " + path + ": not found");
  auto ini = std::make_unique<mrpt::config::CConfigFile>(path);
  ini->discardSavingChanges();
  return ini;
}

std::vector<SensorSection> sectionsOf(const mrpt::config::CConfigFile& ini) {
  std::vector<std::string> names;
  ini.getAllSections(names);
  std::vector<SensorSection> out;
  for (const auto& n : names) {
    const std::string driver = ini.read_string(n, "driver", "");
    // rawlog-grabber skips sections so marked (a sensor's calibration sub-sections).
    if (!driver.empty() && !ini.read_bool(n, "rawlog-grabber-ignore", false)) {
      out.push_back({n, driver});
    }
  }
  return out;
}

std::string where(const std::string& path, const std::string& section) {
  return "sensor file " + path + " [" + section + "]";
}

// The section to open: the one named, or the only one with a driver.
SensorSection pickSection(const mrpt::config::CConfigFile& ini, const std::string& path,
                          const std::string& section) {
  const auto all = sectionsOf(ini);
  if (section.empty()) {
    if (all.size() == 1) return all[0];
    std::string names;
    for (const auto& s : all) names += (names.empty() ? "" : ", ") + s.name;
    throw std::runtime_error("sensor file " + path + ": " +
                             (all.empty() ? std::string("no section has a `driver` key")
                                          : "several sensor sections (" + names +
                                                "): choose one with --sensor-section"));
  }
  for (const auto& s : all) {
    if (s.name == section) return s;
  }
  throw std::runtime_error(where(path, section) + ": no such section with a `driver` key");
}

std::unique_ptr<detail::SensorDriver> createSensor(const std::string& path,
                                                  const SensorSection& s) {
  auto sensor = detail::sensorDrivers().create(s.driver);
  if (!sensor) {
    throw std::runtime_error(where(path, s.name) + ": unknown driver class '" + s.driver +
                             "' (not a sensor of MRPT's hwdrivers)");
  }
  return sensor;
}

void loadSensorConfig(detail::SensorDriver& sensor,
                      const mrpt::config::CConfigFile& ini, const std::string& path,
                      const std::string& section) {
  try {
    sensor.loadConfig(ini, section);
  } catch (const std::exception& e) {
    throw std::runtime_error(where(path, section) + ": bad configuration: " +
                             detail::condenseMessage(e.what()));
  }
}

// MRPT's COpenNI2Sensor aborts the process in doProcess() when no device is attached (the
// probe: sensorDrivers().openni2Devices).
int connectedOpenNI2Devices() { return detail::sensorDrivers().openni2Devices(); }

void requireOpenNI2Device(const std::string& path, const std::string& section) {
  if (connectedOpenNI2Devices() <= 0) {
    throw std::runtime_error(where(path, section) +
                             ": cannot open COpenNI2Sensor: no OpenNI2 device is connected");
  }
}

// The stereo calibration keys of ours, when the section has them.
std::optional<StereoCalibration> stereoCalibration(const mrpt::config::CConfigFile& ini,
                                                   const std::string& path,
                                                   const std::string& section) {
  const std::string left = ini.read_string(section, "upd_stereo_calib_left", "");
  const std::string right = ini.read_string(section, "upd_stereo_calib_right", "");
  if (left.empty() && right.empty()) return std::nullopt;
  if (left.empty() || right.empty()) {
    throw std::runtime_error(where(path, section) +
                             ": set both upd_stereo_calib_left and upd_stereo_calib_right");
  }
  const fs::path dir = fs::path(path).parent_path();
  auto resolve = [&](const std::string& f) {
    return fs::path(f).is_absolute() ? f : (dir / f).string();
  };
  StereoCalibration c = loadStereoCalibrationYaml(resolve(left), resolve(right));
  c.validate();
  return c;
}

void completeStereo(mrpt::obs::CObservationStereoImages& o, const StereoCalibration& c) {
  mrpt::img::TCamera cam;
  cam.ncols = static_cast<uint32_t>(c.width);
  cam.nrows = static_cast<uint32_t>(c.height);
  cam.setIntrinsicParamsFromValues(c.fx_px, c.fy_px, c.cx_px, c.cy_px);
  cam.dist.fill(0);
  o.leftCamera = cam;
  o.rightCamera = cam;
  o.rightCameraPose = mrpt::poses::CPose3DQuat(c.baseline_m, 0, 0, mrpt::math::CQuaternionDouble());
  o.hasImageRight = !o.imageRight.isEmpty();
}

}  // namespace

struct MrptSensorSource::Impl {
  std::string path;
  SensorSection section;
  std::unique_ptr<mrpt::config::CConfigFile> ini;
  std::unique_ptr<detail::SensorDriver> sensor;
  std::optional<StereoCalibration> stereo;
  bool recording = false;
};

std::vector<SensorSection> listSensorSections(const std::string& ini_path) {
  return sectionsOf(*openIni(ini_path));
}

void checkSensorSection(const std::string& ini_path, const std::string& section) {
  const auto ini = openIni(ini_path);
  const SensorSection s = pickSection(*ini, ini_path, section);
  auto sensor = createSensor(ini_path, s);
  loadSensorConfig(*sensor, *ini, ini_path, s.name);
  stereoCalibration(*ini, ini_path, s.name);
  if (s.driver == "COpenNI2Sensor" && connectedOpenNI2Devices() <= 0) {
    // MRPT 2.5's ~COpenNI2Sensor throws (std::terminate) when no device was opened: such an
    // object, which never opened anything, is deliberately kept (reachable) and not destroyed.
    static auto* const never_destroyed = new std::vector<std::unique_ptr<detail::SensorDriver>>();
    static std::mutex guard;
    const std::lock_guard<std::mutex> lock(guard);
    never_destroyed->push_back(std::move(sensor));
  }
}

MrptSensorSource::MrptSensorSource(const std::string& ini_path, const std::string& section)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.path = ini_path;
  m.ini = openIni(ini_path);
  m.section = pickSection(*m.ini, ini_path, section);
  m.stereo = stereoCalibration(*m.ini, ini_path, m.section.name);
  const std::string grabber = m.ini->read_string(m.section.name, "grabber_type", "");
  m.recording = m.section.driver == "CCameraSensor" && (grabber == "image_dir" || grabber == "rawlog");
  if (m.section.driver == "COpenNI2Sensor") requireOpenNI2Device(ini_path, m.section.name);
  m.sensor = createSensor(ini_path, m.section);
  loadSensorConfig(*m.sensor, *m.ini, ini_path, m.section.name);
  try {
    m.sensor->initialize();
  } catch (const std::exception& e) {
    const std::string hint = m.section.driver == "CKinect"
                                 ? " (this MRPT has no libfreenect: use `upd live --kinect`)"
                                 : "";
    throw std::runtime_error(where(ini_path, m.section.name) + ": cannot open " +
                             m.section.driver + ": " + detail::condenseMessage(e.what()) + hint);
  }
}

MrptSensorSource::~MrptSensorSource() = default;

bool MrptSensorSource::poll(std::vector<std::shared_ptr<mrpt::obs::CObservation>>& out) {
  Impl& m = *impl_;
  std::vector<std::shared_ptr<mrpt::obs::CObservation>> got;
  try {
    m.sensor->process(got);
  } catch (const std::exception& e) {
    if (m.recording) return false;  // "Reached end index.", the rawlog's end
    throw std::runtime_error(where(m.path, m.section.name) + ": " + m.section.driver +
                             " failed: " + detail::condenseMessage(e.what()));
  }
  if (m.sensor->failed()) {
    throw std::runtime_error(where(m.path, m.section.name) + ": " + m.section.driver +
                             " reports an error state");
  }
  for (auto& obs : got) {
    if (m.stereo) {
      if (auto* st = dynamic_cast<mrpt::obs::CObservationStereoImages*>(obs.get())) {
        completeStereo(*st, *m.stereo);
      }
    }
    out.push_back(std::move(obs));
  }
  return true;
}

bool MrptSensorSource::isRecording() const { return impl_->recording; }

std::string MrptSensorSource::description() const {
  return impl_->path + " [" + impl_->section.name + "] " + impl_->section.driver;
}

const std::string& MrptSensorSource::driver() const { return impl_->section.driver; }

}  // namespace upd::mrpt_bridge
