// Class maps: the semantic classes of a labelled LiDAR data set (SemanticKITTI, RELLIS-3D) to
// traversability, so their per-point labels become a ground truth for `upd evaluate`.
//
// A class map is a text file, one class per line: `ID CLASS [NAME ...]` where ID is the
// class id (0 .. 65535, the lower 16 bits of a `.label` entry) and CLASS is `traversable`,
// `non-traversable` or `ignore` (no truth: the point is not scored). `#` starts a comment;
// blank lines are skipped. The shipped maps live in share/class_maps/ (semantic-kitti.txt,
// rellis-3d.txt) and say why each class is where it is. Errors are std::runtime_error naming
// the file and line, or the label file and the class id it holds that the map lacks.
#pragma once

#include "upd/core/point_cloud.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace upd::io {

struct ClassMap {
  std::string path;  ///< where it was read from (for messages)
  /// class id -> Traversable, NonTraversable, or Unknown for `ignore`.
  std::map<std::uint16_t, core::Label> classes;
  std::map<std::uint16_t, std::string> names;  ///< class id -> name (may be empty)
};

/// Reads a class map; throws std::runtime_error "FILE:LINE: ..." for a bad line, a duplicate
/// id, or a file with no class.
ClassMap readClassMap(const std::string& path);

/// The truth of every point of a SemanticKITTI / RELLIS-3D `.label` file (already read, one
/// uint32 per point). Throws std::runtime_error naming labels_path and the first class id
/// the map does not list.
std::vector<core::Label> truthFromLabels(const std::vector<std::uint32_t>& labels,
                                         const ClassMap& map, const std::string& labels_path);

}  // namespace upd::io
