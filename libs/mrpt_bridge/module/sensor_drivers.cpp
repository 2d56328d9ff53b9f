// The sensors module (sensor_driver.h): MRPT's hwdrivers behind SensorDriver.
#include "../src/sensor_driver.h"

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/hwdrivers/CGenericSensor.h>
#include <mrpt/hwdrivers/COpenNI2Generic.h>
#include <mrpt/obs/CObservation.h>

namespace upd::mrpt_bridge::detail {

namespace {

class MrptDriver final : public SensorDriver {
 public:
  explicit MrptDriver(mrpt::hwdrivers::CGenericSensor::Ptr s) : s_(std::move(s)) {}
  void loadConfig(const mrpt::config::CConfigFileBase& ini, const std::string& section) override {
    s_->loadConfig(ini, section);
  }
  void initialize() override { s_->initialize(); }
  void process(std::vector<std::shared_ptr<mrpt::obs::CObservation>>& out) override {
    mrpt::hwdrivers::CGenericSensor::TListObservations got;
    s_->doProcess();
    s_->getObservations(got);
    for (auto& [t, obj] : got) {
      if (auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj)) {
        out.push_back(std::move(obs));
      }
    }
  }
  bool failed() const override {
    return s_->getState() == mrpt::hwdrivers::CGenericSensor::ssError;
  }

 private:
  mrpt::hwdrivers::CGenericSensor::Ptr s_;
};

std::unique_ptr<SensorDriver> create(const std::string& driver) {
  auto sensor = mrpt::hwdrivers::CGenericSensor::createSensorPtr(driver);
  if (!sensor) return nullptr;
  return std::make_unique<MrptDriver>(std::move(sensor));
}

// OpenNI2 stays initialized from the first probe until the process ends: MRPT's
// COpenNI2Generic shuts it down when its last instance goes, which unloads the device drivers
// (and with them what they allocated, then lost to every tool that would name it). The one
// probe is never destroyed and stays reachable.
int openni2Devices() {
  static auto* const probe = new mrpt::hwdrivers::COpenNI2Generic();
  return probe->getConnectedDevices();
}

}  // namespace

}  // namespace upd::mrpt_bridge::detail

extern "C" const upd::mrpt_bridge::detail::SensorDrivers upd_mrpt_sensor_drivers = {
    &upd::mrpt_bridge::detail::create, &upd::mrpt_bridge::detail::openni2Devices};
