// ROC curves as a PNG: the false-positive rate against the true-positive rate of several
// detectors on one data set, one line per detector with its AUC in the legend, the chance
// diagonal dashed. Drawn with CImage primitives like the zeta histogram (figure.h) and written
// through a temporary file renamed into place.
#pragma once

#include <string>
#include <vector>

namespace upd::nav {

struct RocSeries {
  std::string label;             ///< legend text (the AUC is appended)
  std::vector<double> fpr, tpr;  ///< the curve, from (0, 0) to (1, 1)
  double auc = 0;
};

/// Throws std::invalid_argument for no series, a series whose fpr and tpr differ in size, or a
/// size outside 400x300 .. 4096x4096; std::runtime_error when the PNG cannot be written.
void drawRocCurves(const std::vector<RocSeries>& series, const std::string& title,
                   const std::string& png, int width = 900, int height = 800);

}  // namespace upd::nav
