// Reading and writing point clouds: PCD (through PCL), PLY (own reader and writer) and XYZ text,
// and the scored PLY that holds the per-point UPD results.
//
// This is the one place where cloud file formats are parsed, so every app and test loads a
// cloud the same way. Readers keep what the file says: an organized PCD stays width x height
// with its NaN pixels (nothing is dropped: the pipeline counts them), the PCD viewpoint becomes
// PointCloud::sensor_origin, and colour is kept when the file has it. Every failure (missing
// file, unknown extension, corrupt or truncated data, a cloud without x/y/z) is a
// std::runtime_error with a one-line message that names the file and what is wrong.
// Writers go through writeFileAtomically (see atomic_file.h).
//
// The scored PLY (writeScoredPly) carries every per-point result as a vertex property, so
// CloudCompare and MeshLab can colour by zeta or filter by label. Its writer takes views
// (pointer + length) rather than a PipelineResult, so a caller that keeps points and results in
// other buffers (the MRPT observer views a CPointsMap's x, y, z vectors) writes the same file
// without copying. The property order is the format's contract: x y z nx ny nz scalar_rx
// scalar_ry scalar_rz scalar_zeta scalar_label scalar_cost quality, then red green blue when
// there is colour (all float except the uchar label and colour). The names follow the viewers:
// CloudCompare loads a property whose name starts with `scalar_` as a scalar field (its
// command-line mode loads no other extra property) and nx ny nz as normals; MeshLab shows
// `quality` (a copy of zeta). By default only points with a finite x, y and z are written:
// viewers read a NaN coordinate as 0, a cluster at the origin.
#pragma once

#include "upd/core/pipeline.h"
#include "upd/core/point_cloud.h"

#include <cstddef>
#include <cstdint>
#include <istream>
#include <string>
#include <vector>

namespace upd::io {

/// Reads a cloud, choosing the format by the extension (case-insensitive): .pcd, .ply,
/// .xyz or .txt (XYZ text), .bin (a KITTI scan, kitti_bin.h). Any other extension throws
/// std::runtime_error naming the file and the supported extensions; so does a PCD, PLY or
/// gzip file under another extension (naming what it is).
core::PointCloud readCloud(const std::string& path);

/// PCD of any DATA kind (ascii, binary, binary_compressed). Fields x, y, z are required (any
/// numeric type); colour is read from `rgb` (float-packed) or `rgba` (uint32); other fields are
/// ignored. sensor_origin is the VIEWPOINT translation (its rotation is not kept).
core::PointCloud readPcd(const std::string& path);

/// PLY `format ascii 1.0`, `binary_little_endian 1.0` or `binary_big_endian 1.0`. Reads the
/// vertex element's x, y, z (any numeric type) and red, green, blue when present (uchar; other
/// integer types are clamped to 0..255, float types are taken as 0..1); every other property
/// and element (faces with list properties included) is skipped. A header line `comment
/// sensor_origin X Y Z` (written by writePly and writeScoredPly) sets sensor_origin.
core::PointCloud readPly(const std::string& path);

/// XYZ text: one point per line, `x y z` or `x y z r g b` (r, g, b in 0..255), separated by
/// whitespace and/or commas. `#` starts a comment; blank lines are ignored; a first line with
/// no number at all (a column header such as `x,y,z`) is skipped. Every point line must have
/// the column count of the first one. A bad line throws, naming the file and the line number.
core::PointCloud readXyz(const std::string& path);

/// Options of the PLY writers.
struct PlyWriteOptions {
  /// Skip points with a NaN or infinite coordinate (some viewers handle them badly). Off by
  /// default: then vertex i is point i, so the file lines up with the cloud and its results.
  bool drop_non_finite_xyz = false;
  /// Extra header comment lines (e.g. the command line that made the file).
  std::vector<std::string> comments;
};

/// Writes a binary little-endian PLY with vertex properties `x y z`, then `label` (uchar, the
/// Label values) when labels is given, then `red green blue` (uchar) when the cloud has
/// colour. labels, when given, must hold one entry per point (else std::invalid_argument).
/// A sensor_origin other than (0, 0, 0) is kept as the header line `comment sensor_origin X Y Z`.
void writePly(const std::string& path, const core::PointCloud& cloud,
              const std::vector<core::Label>* labels = nullptr, const PlyWriteOptions& options = {});

/// Writes XYZ text (`x y z` or `x y z r g b` per line); the floats are written in their
/// shortest exact form, so readXyz gives back the same values.
void writeXyz(const std::string& path, const core::PointCloud& cloud);

/// Writes a binary PCD (fields x y z, plus rgb when the cloud has colour) with width x height
/// kept for an organized cloud and the VIEWPOINT set from sensor_origin.
void writePcd(const std::string& path, const core::PointCloud& cloud);

/// A read-only view of n contiguous values (pre-C++20 std::span). Builds implicitly from a
/// std::vector; empty means "absent".
template <class T>
struct ArrayView {
  const T* data = nullptr;
  std::size_t size = 0;

  ArrayView() = default;
  ArrayView(const T* d, std::size_t n) : data(d), size(n) {}
  ArrayView(const std::vector<T>& v) : data(v.data()), size(v.size()) {}  // NOLINT: implicit

  bool empty() const { return size == 0; }
  const T& operator[](std::size_t i) const { return data[i]; }
};

/// Per-point arrays to write. x, y, z are required and set the point count n; every other view
/// is empty (absent) or holds n values. Absent floats are written as NaN, an absent label as
/// Label::Unknown; colour is written only when r, g and b are all present.
struct ScoredPoints {
  ArrayView<float> x, y, z;
  ArrayView<float> nx, ny, nz;        ///< unit normal
  ArrayView<float> rx, ry, rz, zeta;  ///< UPD vector r (eq. 6) and zeta (eq. 8)
  ArrayView<core::Label> label;
  ArrayView<float> cost;              ///< traversal cost in [0, 1]
  ArrayView<std::uint8_t> r, g, b;    ///< colour

  /// The image layout of an organized cloud (width x height == size()), else 0 x 0; written
  /// as header comments `width W` and `height H` by the organized scored PLY.
  std::size_t width = 0, height = 0;

  std::size_t size() const { return x.size; }
  /// Throws std::invalid_argument naming the first view whose size is neither 0 nor n (x, y,
  /// z must all be n), or when only some of r, g, b are present.
  void validate() const;
};

/// Views of a pipeline result (its scored cloud, normals, UPD and classes). The result must
/// outlive the returned views.
ScoredPoints scoredPointsOf(const core::PipelineResult& result);

/// Options of the scored PLY writer.
struct ScoredPlyOptions {
  /// Every point, vertex i = point i, NaN rows included (and `width`/`height` comments when
  /// the points are organized), so the file lines up pixel by pixel with the image. Off by
  /// default: points with a NaN or infinite x, y or z are left out.
  bool organized = false;
  /// Extra header comment lines (e.g. the command line that made the file).
  std::vector<std::string> comments;
};

/// Writes a binary little-endian PLY with the properties listed in the header comment.
/// Throws std::invalid_argument for inconsistent sizes, std::runtime_error for I/O failures.
void writeScoredPly(const std::string& path, const ScoredPoints& points,
                    const ScoredPlyOptions& options = {});
void writeScoredPly(const std::string& path, const core::PipelineResult& result,
                    const ScoredPlyOptions& options = {});

/// The vertex property names writeScoredPly writes, in order (colour not included).
const std::vector<std::string>& scoredPlyProperties();

/// A scored PLY read back: the cloud (colour and sensor_origin when the file has them) and its
/// per-point results, one entry per vertex.
struct ScoredPly {
  core::PointCloud cloud;
  std::vector<float> nx, ny, nz;
  std::vector<float> rx, ry, rz;  ///< NaN for every vertex when the file lacks scalar_rx/ry/rz
  std::vector<float> zeta, cost;
  std::vector<core::Label> label;  ///< 0, 1, 2 as written; any other value (NaN, -5, 0.5) Unknown
};

/// Reads a scored PLY (writeScoredPly's file, or one another tool re-saved: any PLY encoding,
/// any scalar type per property, other properties and elements skipped) through readPly's
/// parser. x y z nx ny nz scalar_zeta scalar_label scalar_cost are required: a file without one
/// throws std::runtime_error naming the file and the property, as readPly does for bad data.
/// Organized files come back unorganized (width = n, height = 1).
ScoredPly readScoredPly(const std::string& path);

/// The names of a PLY file's vertex properties, in order (its header checked as readPly checks
/// it): what tells a scored PLY (scalar_zeta) from a raw cloud.
std::vector<std::string> plyVertexProperties(const std::string& path);

/// Lower-cased extension of path including the dot (".pcd"), or "" when it has none.
std::string lowerExtension(const std::string& path);

}  // namespace upd::io
