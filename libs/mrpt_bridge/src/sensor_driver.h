// One MRPT sensor (CGenericSensor) as MrptSensorSource drives it, behind an interface: its
// implementation is the sensors module (module/sensor_drivers.cpp, MRPT's hwdrivers), loaded
// when the first sensor is opened (module.h), so that no other command loads hwdrivers.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace mrpt::config {
class CConfigFileBase;
}
namespace mrpt::obs {
class CObservation;
}

namespace upd::mrpt_bridge::detail {

class SensorDriver {
 public:
  virtual ~SensorDriver();
  /// CGenericSensor::loadConfig(ini, section); throws as MRPT does.
  virtual void loadConfig(const mrpt::config::CConfigFileBase& ini, const std::string& section) = 0;
  /// CGenericSensor::initialize(); throws as MRPT does.
  virtual void initialize() = 0;
  /// doProcess() then getObservations(): the observations appended, oldest first (objects
  /// that are not observations dropped). Throws as MRPT does.
  virtual void process(std::vector<std::shared_ptr<mrpt::obs::CObservation>>& out) = 0;
  /// The sensor is in its error state (ssError).
  virtual bool failed() const = 0;
};

/// The sensors module's entry points.
struct SensorDrivers {
  /// CGenericSensor::createSensorPtr(driver), or null when MRPT has no sensor class of that name.
  std::unique_ptr<SensorDriver> (*create)(const std::string& driver);
  /// The number of OpenNI2 devices connected (OpenNI2 stays initialized for the process).
  int (*openni2Devices)();
};

/// The entry points, the module loaded on first use (a static build: linked in).
const SensorDrivers& sensorDrivers();

}  // namespace upd::mrpt_bridge::detail

/// The sensors module's one exported symbol.
extern "C" const upd::mrpt_bridge::detail::SensorDrivers upd_mrpt_sensor_drivers;
