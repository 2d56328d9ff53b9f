// Per-point scores and features for labelled evaluation and the learned classifier.
//
// The continuous scores the evaluation ranks (each higher = more likely non-traversable once
// turned by scoreOf into one): at every d_m the UPD (zeta, eq. 8, and the slope of r, eq. 6),
// the roughness index and the inclination index (baselines.h); and, independent of d_m, the
// slope of the point's own PCA normal ("slope alone") and the height range of the point's
// cell_m x cell_m column (max - min of the elevation along up of the points in the cell).
//
// The feature vector of the learned classifier (kFeatureNames, in this order): for each of
// the three radii of FeatureParams the zeta, the slope of r [rad], the roughness index [m]
// and the inclination index [rad]; then the normal's slope [rad], the cell's height range and
// height spread (standard deviation of elevation) [m], the density (points within the
// smallest radius per m^2 of its disc) and the distance from the sensor [m]. A value that
// cannot be computed (too few neighbours) is -1: every feature is >= 0 otherwise, so a tree
// separates "missing" with one split.
#pragma once

#include "upd/core/baselines.h"
#include "upd/core/kdtree.h"
#include "upd/core/normals.h"
#include "upd/core/params.h"
#include "upd/core/upd.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace upd::core {

/// The features of the learned classifier; a model file stores the ones it was trained with.
struct FeatureParams {
  double radius_small_m = 0.3;  ///< the first d_m of the UPD and baselines [m]
  double radius_m = 0.5;        ///< the second [m]
  double radius_large_m = 1.0;  ///< the third [m]
  double cell_m = 0.5;          ///< height-range column size [m]
  int min_neighbors = 5;        ///< fewer neighbours: the radius' features are missing (-1)

  void validate() const;
  std::vector<double> radii() const { return {radius_small_m, radius_m, radius_large_m}; }
  template <class V>
  void visit(V& v) {
    v("radius_small_m", radius_small_m, "first d_m of the classifier's UPD and baselines [m]");
    v("radius_m", radius_m, "second d_m [m]");
    v("radius_large_m", radius_large_m, "third d_m [m]");
    v("cell_m", cell_m, "column size of the height range and spread features [m]");
    v("min_neighbors", min_neighbors, "fewer neighbours: the features at that d_m are missing");
  }
};

constexpr int kFeatureCount = 17;
/// The names of the features, in the order of a row of PointFeatures.
extern const char* const kFeatureNames[kFeatureCount];

/// The scores at one d_m.
struct RadiusScores {
  double radius_m = 0;
  UpdResult upd;
  std::vector<float> upd_slope_rad;  ///< angle between r and up; NaN where no UPD
  BaselineResult baselines;          ///< roughness and inclination indices
};

struct PointScores {
  std::vector<RadiusScores> radii;       ///< in the order asked for
  std::vector<float> normal_slope_rad;   ///< angle between the normal and up, [0, pi/2]
  std::vector<float> height_range_m;     ///< the cell's max - min elevation [m]
  std::vector<float> height_spread_m;    ///< the cell's std dev of elevation [m]
  std::vector<float> range_m;            ///< distance from the sensor origin [m]

  /// The scores at radius_m (exactly as asked for); throws std::invalid_argument if absent.
  const RadiusScores& at(double radius_m) const;
};

/// Every score of every point of cloud (indexed by tree) with normals (unit, NaN where none)
/// and unit up, at each of radii_m (exact k-d tree sums), with cell_m columns. min_neighbors
/// as in BaselineParams (the UPD's min_neighbors stays its default).
PointScores computePointScores(const PointCloud& cloud, const KdTree& tree,
                               const Normals& normals, const Eigen::Vector3f& up,
                               const std::vector<double>& radii_m, double cell_m,
                               int min_neighbors);

/// Row-major n x kFeatureCount features. scores must hold FeatureParams' three radii.
std::vector<float> featuresOf(const PointScores& scores, const FeatureParams& params);

/// The same from scratch: the scores at FeatureParams' radii, then the features.
std::vector<float> computeFeatures(const PointCloud& cloud, const Normals& normals,
                                   const Eigen::Vector3f& up, const FeatureParams& params);

/// The cell_m x cell_m column (square cells in the plane normal to up) of every point, as
/// dense indices 0 .. columns - 1 (columns receives the count); kNoColumn for a point with no
/// finite position.
constexpr std::uint32_t kNoColumn = 0xffffffffu;
std::vector<std::uint32_t> columnIndex(const PointCloud& cloud, const Eigen::Vector3f& up,
                                       double cell_m, std::size_t& columns);

/// The height range and spread of each point's cell_m column (cells square in the plane
/// normal to up; points with no finite position get NaN).
void columnHeightStats(const PointCloud& cloud, const Eigen::Vector3f& up, double cell_m,
                       std::vector<float>& range_m, std::vector<float>& spread_m);

}  // namespace upd::core
