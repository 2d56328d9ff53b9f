// KITTI and SemanticKITTI LiDAR scans: `velodyne/NNNNNN.bin`, a headerless array of
// little-endian float32 records (x, y, z, intensity), x forward, y left, z up [m] in the
// sensor's frame (so the UPD's default up, 0,0,1, is right), and SemanticKITTI's
// `labels/NNNNNN.label`, one little-endian uint32 per point (the semantic class in the lower 16
// bits, the instance id in the upper 16).
//
// A .bin has no header, so the reader checks what it can: the size is a whole number of
// 16-byte records, and the content is not another format under the wrong extension (a PCD, a
// PLY, text, gzip). Coordinates are kept as they are (NaN and Inf included: the pipeline counts
// them). Errors are std::runtime_error naming the file, as for every reader in cloud_io.h.
#pragma once

#include "upd/core/point_cloud.h"

#include <cstdint>
#include <string>
#include <vector>

namespace upd::io {

/// One scan: the points, and the intensity (reflectance, 0..1 in KITTI) of each.
struct KittiScan {
  core::PointCloud cloud;
  std::vector<float> intensity;  ///< one per point
};

/// Reads a KITTI `.bin` scan (16 bytes per point). An empty file is a scan of no points; a size
/// that is not a multiple of 16 is a truncated or foreign file and throws naming the size.
KittiScan readKittiBin(const std::string& path);

/// Writes a KITTI `.bin` scan atomically; intensity is empty (written as 0) or one per point.
void writeKittiBin(const std::string& path, const core::PointCloud& cloud,
                   const std::vector<float>& intensity = {});

/// SemanticKITTI point labels (`.label`: one uint32 per point). points, when non-zero, is the
/// scan's point count, which the file must match.
std::vector<std::uint32_t> readSemanticKittiLabels(const std::string& path,
                                                   std::size_t points = 0);

/// The semantic class of a SemanticKITTI label (its lower 16 bits).
inline std::uint16_t semanticClassOf(std::uint32_t label) {
  return static_cast<std::uint16_t>(label & 0xffffu);
}

}  // namespace upd::io
