// The real stereo pairs of ../shared/data/rtabmap/stereo_rect laid out as MRPT's image_dir
// grabber reads them (left_0.jpg, right_0.jpg, left_1.jpg, ...), with their calibration files
// and a sensor file naming them: a stereo camera without hardware.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace upd::test {

/// Copies the pairs 50 and 60 and the calibration into dir and writes dir/stereo.ini (section
/// [STEREO]); extra_keys are appended to the section. Returns the ini path.
inline std::string writeStereoImageDir(const std::filesystem::path& data,
                                       const std::filesystem::path& dir,
                                       const std::string& extra_keys = "",
                                       bool calibration_keys = true) {
  namespace fs = std::filesystem;
  const char* frames[] = {"50", "60"};
  for (int i = 0; i < 2; ++i) {
    const std::string n = std::to_string(i);
    fs::copy_file(data / "left" / (std::string(frames[i]) + ".jpg"), dir / ("left_" + n + ".jpg"));
    fs::copy_file(data / "right" / (std::string(frames[i]) + ".jpg"),
                  dir / ("right_" + n + ".jpg"));
  }
  fs::copy_file(data / "stereo_left.yaml", dir / "stereo_left.yaml");
  fs::copy_file(data / "stereo_right.yaml", dir / "stereo_right.yaml");
  const std::string ini = (dir / "stereo.ini").string();
  std::ofstream out(ini);
  out << "[STEREO]\ndriver = CCameraSensor\nsensorLabel = STEREO\ngrabber_type = image_dir\n"
      << "image_dir_url = " << dir.string() << "\nleft_format = left_%d.jpg\n"
      << "right_format = right_%d.jpg\nstart_index = 0\nend_index = 1\n"
      << "pose_x = 0.3\npose_z = 0.5\npose_yaw = -90\npose_roll = -90\n";
  if (calibration_keys) {
    out << "upd_stereo_calib_left = stereo_left.yaml\nupd_stereo_calib_right = stereo_right.yaml\n";
  }
  out << extra_keys;
  return ini;
}

}  // namespace upd::test
