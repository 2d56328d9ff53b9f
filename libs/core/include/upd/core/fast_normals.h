// PCA normals (paper eqs. 4-5) without a k-d tree: image-window scans for organized clouds, a
// hash grid for unorganized ones. Both find the exact path's neighbourhoods (all points within
// NormalParams::radius_m); what makes the organized path fast is where it looks and how often.
//
// Organized clouds (a depth image back-projected, width x height with NaN holes): the ball of
// radius r around a point at range rho subtends asin(r / rho) each way, so its points lie in a
// small image window (its half-width is that angle over the angular pitch of a pixel, measured
// from the cloud's own rays: no intrinsics needed). The window is scanned, a vector of pixels
// at a time, and the points within r in 3D are kept: the same neighbourhood as a k-d tree
// radius search, without building or walking a tree. Near the sensor, where a ball spans more
// than fast_scan_px pixels (48), every 2nd or 4th row and column is scanned (a regular sample
// of hundreds of its points). One normal is computed per block of fast_block_px x fast_block_px
// pixels, at its centre. A pixel takes the normal of the nearest block centre on its surface (range
// within max_depth_jump_ratio of the pixel's): its own block's, else the closest in range of
// the 8 blocks around it. A pixel with none (a depth edge, a thin object) computes its own.
// The UPD sums thousands of normals per point, so sharing changes zeta by about 1e-3 while
// cutting the work by about fast_block_px^2. The normal is
// the eigenvector of the smallest eigenvalue (eq. 5), found without a general eigen solver (see
// normalFromMoments in fast_normals.cpp), and oriented by the rule of normals.h.
//
// Why not integral images of the point moments (an O(1) rectangle per pixel, as PCL's
// IntegralImageNormalEstimation): on real Kinect frames the depth is quantized in steps of
// 2.85e-3 z^2 (7 cm at 5 m), and a pixel rectangle mixes treads of that staircase that the 3D
// ball keeps apart. Measured on pcl/office1.pcd: rectangle normals were a median 24 degrees
// (r = 0.05 m) and 15 degrees (r = 0.1 m) from the ball's, and zeta 0.26 and 0.09 lower on
// average; with the scans zeta stays within 0.001-0.003 of the exact path (docs/PERFORMANCE.md).
//
// Unorganized clouds: computeNormalsGrid bins the points in cells of edge radius_m; the
// neighbours of a point lie in the 27 cells around its own. Same neighbours as the exact path,
// so the same normals up to the order of summation.
#pragma once

#include "upd/core/normals.h"
#include "upd/core/point_cloud.h"

namespace upd::core {

/// True when computeNormalsOrganized accepts cloud and params: an organized cloud, a radius
/// neighbourhood (knn = 0) and uniform weights.
bool organizedNormalsApply(const PointCloud& cloud, const NormalParams& params);

/// Normals of an organized cloud by window scans (header comment); NaN where a normal cannot
/// be computed (non-finite pixel, fewer than 3 points, collinear), counted in
/// Normals::invalid. Throws std::invalid_argument when !organizedNormalsApply(cloud, params).
/// A cloud whose rays give no angular pitch (too few valid neighbouring pixels) falls back to
/// computeNormalsGrid. up must be unit length.
Normals computeNormalsOrganized(const PointCloud& cloud, const NormalParams& params,
                                const Eigen::Vector3f& up);

/// The same into out, whose buffers are reused (a frame loop allocates nothing once warm).
void computeNormalsOrganized(const PointCloud& cloud, const NormalParams& params,
                             const Eigen::Vector3f& up, Normals& out);

/// Normals of any cloud with the radius neighbourhoods of computeNormals (params.knn must be 0,
/// else std::invalid_argument), found by a hash grid instead of a k-d tree: the same normals
/// up to the order of summation; Gaussian weights are supported. up must be unit length.
Normals computeNormalsGrid(const PointCloud& cloud, const NormalParams& params,
                           const Eigen::Vector3f& up);
/// The same into out, whose buffers are reused.
void computeNormalsGrid(const PointCloud& cloud, const NormalParams& params,
                        const Eigen::Vector3f& up, Normals& out);

}  // namespace upd::core
