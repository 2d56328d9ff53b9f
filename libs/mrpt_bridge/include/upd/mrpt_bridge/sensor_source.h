// MRPT's sensor framework as a source of observations: one sensor section of an ini file in the
// format MRPT's rawlog-grabber reads (`[SECTION] driver = CCameraSensor`, then the driver's own
// keys), driven as rawlog-grabber drives it: CGenericSensor::createSensorPtr(driver),
// loadConfig(file, section), initialize(), then doProcess() + getObservations() per poll.
//
// Every sensor MRPT drives is a source (COpenNI2Sensor, CCameraSensor with its grabbers,
// CVelodyneScanner, ...); which of its observations the UPD can score is decided later
// (observation_cloud.h). Two traps of MRPT 2.5 are handled here:
//  - COpenNI2Sensor without a device aborts the process in doProcess(): the OpenNI2 devices are
//    listed first and the source fails with one line when there is none.
//  - CCameraSensor's `image_dir` grabber returns CObservationStereoImages with hasImageRight = 0
//    and no calibration. The section may carry keys of ours (MRPT ignores unknown keys):
//      upd_stereo_calib_left  = FILE.yaml   left camera, OpenCV/ROS YAML (stereo.h)
//      upd_stereo_calib_right = FILE.yaml   right camera (its projection gives the baseline)
//    relative to the ini file's folder; each stereo observation then gets that calibration
//    (leftCamera, rightCamera, rightCameraPose) and hasImageRight is set when the right image
//    is there, so that the observation is complete in a recording too.
// A sensor that replays files (image_dir, rawlog) ends when MRPT says it reached the end.
// Errors (an unknown driver class, a section that is missing or holds no driver, a sensor that
// fails to open) throw std::runtime_error with one line naming the file and section.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace mrpt::obs {
class CObservation;
}

namespace upd::mrpt_bridge {

/// A section of a sensor file that names a driver.
struct SensorSection {
  std::string name;    ///< the ini section
  std::string driver;  ///< its `driver` key: the MRPT class name
};

/// The sections of ini_path that have a `driver` key, in file order. Throws std::runtime_error
/// when the file is missing.
std::vector<SensorSection> listSensorSections(const std::string& ini_path);

/// Creates the section's sensor and loads its configuration without opening the device: what
/// checks an example sensor file. Throws like MrptSensorSource's constructor.
void checkSensorSection(const std::string& ini_path, const std::string& section);

class MrptSensorSource {
 public:
  /// Opens the sensor of section (empty: the file's only section with a `driver` key; an error
  /// when there are none or several).
  explicit MrptSensorSource(const std::string& ini_path, const std::string& section = "");
  ~MrptSensorSource();
  MrptSensorSource(const MrptSensorSource&) = delete;
  MrptSensorSource& operator=(const MrptSensorSource&) = delete;

  /// One doProcess(): appends the observations the sensor delivered, oldest first (none when it
  /// had nothing new). Returns false at the end of a recording: a sensor that replays files
  /// (CCameraSensor with grabber_type image_dir or rawlog) throws at its end, which ends it.
  /// Throws std::runtime_error naming the section when a device fails.
  bool poll(std::vector<std::shared_ptr<mrpt::obs::CObservation>>& out);
  /// The sensor replays files (see poll()).
  bool isRecording() const;

  /// "sensors.ini [CAMERA] CCameraSensor".
  std::string description() const;
  const std::string& driver() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace upd::mrpt_bridge
