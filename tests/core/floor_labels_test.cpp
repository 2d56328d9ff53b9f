// Geometric labels: the floor is traversable, a box on it and the floor's border with it not.
#include "upd/core/floor_labels.h"

#include <gtest/gtest.h>

namespace upd::core {
namespace {

// A floor 1 m below the sensor (camera-like frame, up +z here), with a 0.3 m cube at x 0..0.3.
PointCloud floorWithBox() {
  PointCloud c;
  for (int i = -20; i <= 20; ++i) {
    for (int j = -20; j <= 20; ++j) c.push_back(0.05f * i, 0.05f * j, -1.f);
  }
  for (int i = 0; i <= 6; ++i) {
    for (int j = 0; j <= 6; ++j) c.push_back(0.05f * i, 0.05f * j, -0.7f);  // the box top
  }
  c.push_back(NAN, 0, 0);
  return c;
}

TEST(FloorLabels, FloorBoxAndBorder) {
  const PointCloud c = floorWithBox();
  FloorPlane plane;
  plane.found = true;
  plane.normal = Eigen::Vector3d::UnitZ();
  plane.offset_m = 1.0;  // z = -1
  GeometricLabelParams p;
  p.border_m = 0.12;
  const std::vector<Label> l = labelByFloor(c, plane, p);
  const auto at = [&](float x, float y, float z) {
    for (std::size_t i = 0; i < c.size(); ++i) {
      if (c.isFinite(i) && (c.point(i) - Eigen::Vector3f(x, y, z)).norm() < 1e-4f) return l[i];
    }
    ADD_FAILURE() << "no point at " << x << "," << y << "," << z;
    return Label::Unknown;
  };
  EXPECT_EQ(at(-0.8f, -0.8f, -1.f), Label::Traversable);
  EXPECT_EQ(at(0.1f, 0.1f, -0.7f), Label::NonTraversable);  // the box
  // Under the box edge the floor lies 0.3 m below the box top: not within 0.12 m of it...
  EXPECT_EQ(at(0.1f, 0.1f, -1.f), Label::Traversable);
  // ... but with the box's side sampled from 0.1 m up, the floor beside it is a border.
  PointCloud walled = c;
  for (int k = 2; k <= 5; ++k) walled.push_back(-0.0f, 0.1f, -1.f + 0.05f * k);
  const std::vector<Label> lw = labelByFloor(walled, plane, p);
  EXPECT_EQ(lw[20 * 41 + 22], Label::NonTraversable);  // (0, 0.1, -1): next to the side
  EXPECT_EQ(lw[19 * 41 + 22], Label::NonTraversable);  // (-0.05, 0.1, -1): 0.11 m from it
  EXPECT_EQ(lw[18 * 41 + 22], Label::Traversable);     // (-0.1, 0.1, -1): 0.14 m, beyond
  EXPECT_EQ(l.back(), Label::Unknown);                 // NaN
  plane.found = false;
  EXPECT_THROW(labelByFloor(c, plane, p), std::invalid_argument);
}

}  // namespace
}  // namespace upd::core
