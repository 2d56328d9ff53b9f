// The binary little-endian PLY writer shared by writePly and writeScoredPly, and the vertex
// reader shared by readPly and readScoredPly (not installed): one routine writes every PLY the
// project produces and one parses every PLY it reads, so they cannot drift apart.
#pragma once

#include "upd/core/point_cloud.h"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace upd::io::detail {

/// One vertex property: float or uchar, read from data (n values) or, when data is null,
/// the fill value for every vertex.
struct PlyColumn {
  std::string name;
  bool is_uchar = false;
  const float* f = nullptr;
  const std::uint8_t* u8 = nullptr;
  float fill_f = std::numeric_limits<float>::quiet_NaN();
  std::uint8_t fill_u8 = 0;
};

/// Writes n vertices with the given columns (in order) atomically. With drop_non_finite_xyz
/// the first three columns must be x, y, z and vertices with a non-finite coordinate are
/// skipped. comments go into the header, one `comment` line each (newlines become spaces).
void writeBinaryPly(const std::string& path, std::size_t n, const std::vector<PlyColumn>& columns,
                    const std::vector<std::string>& comments, bool drop_non_finite_xyz);

/// comments with `sensor_origin X Y Z` added when origin is not (0, 0, 0), the origin readPly
/// restores: the "towards the sensor" orientation of vertical normals needs it.
std::vector<std::string> withOriginComment(std::vector<std::string> comments,
                                           const Eigen::Vector3f& origin);

/// A PLY's vertices: the cloud as readPly reads it, and beside it the requested extra vertex
/// properties (any scalar type, as float), one value per vertex where has_extra[k] (empty where
/// the file lacks the property).
struct PlyVertices {
  core::PointCloud cloud;
  std::vector<std::vector<float>> extra;
  std::vector<bool> has_extra;
};

/// Reads the vertices of a PLY in any of its three encodings, with the properties named in
/// extra; throws std::runtime_error naming the file and what is wrong, as readPly does.
PlyVertices readPlyVertices(const std::string& path, const std::vector<std::string>& extra);

}  // namespace upd::io::detail
