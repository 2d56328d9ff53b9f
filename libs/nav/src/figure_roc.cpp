// ROC curves drawn with CImage primitives (figure_roc.h).
#include "upd/nav/figure_roc.h"

#include "figure_png.h"

#include <mrpt/core/format.h>
#include <mrpt/img/CImage.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace upd::nav {
namespace {

using mrpt::img::TColor;

const TColor kColours[] = {TColor(30, 90, 200),  TColor(225, 110, 20), TColor(40, 160, 70),
                           TColor(200, 40, 40),  TColor(130, 60, 170), TColor(90, 90, 90),
                           TColor(20, 170, 190), TColor(190, 150, 20), TColor(230, 80, 160)};

struct Box {
  int x0, y0, x1, y1;  // the plot area, y0 on top
  int px(double v) const { return x0 + int(std::lround(v * (x1 - x0))); }
  int py(double v) const { return y1 - int(std::lround(v * (y1 - y0))); }
};

void drawFrame(mrpt::img::CImage& img, const Box& b, const std::string& title) {
  const TColor grid(225, 225, 225), ink(40, 40, 40);
  img.selectTextFont("9x15");
  for (int k = 0; k <= 5; ++k) {
    const double v = 0.2 * k;
    img.line(b.x0, b.py(v), b.x1, b.py(v), grid);
    img.line(b.px(v), b.y0, b.px(v), b.y1, grid);
    img.textOut(b.x0 - 40, b.py(v) - 7, mrpt::format("%.1f", v), ink);
    img.textOut(b.px(v) - 12, b.y1 + 10, mrpt::format("%.1f", v), ink);
  }
  for (int k = 0; k < 40; k += 2) {  // the chance diagonal, dashed
    img.line(b.px(k / 40.0), b.py(k / 40.0), b.px((k + 1) / 40.0), b.py((k + 1) / 40.0),
             TColor(160, 160, 160));
  }
  img.rectangle(b.x0, b.y0, b.x1, b.y1, ink);
  img.textOut((b.x0 + b.x1) / 2 - 110, b.y1 + 32, "false-positive rate (traversable flagged)", ink);
  img.textOut(b.x0 - 40, b.y0 - 24, "true-positive rate (obstacles found)", ink);
  img.textOut(b.x0, 12, title, ink);
}

}  // namespace

void drawRocCurves(const std::vector<RocSeries>& series, const std::string& title,
                   const std::string& png, int width, int height) {
  if (series.empty()) throw std::invalid_argument("no ROC curve to plot");
  if (width < 400 || height < 300 || width > 4096 || height > 4096) {
    throw std::invalid_argument("ROC plot size " + std::to_string(width) + "x" +
                                std::to_string(height) + " out of range (400x300 to 4096x4096)");
  }
  mrpt::img::CImage img(width, height, mrpt::img::CH_RGB);
  img.filledRectangle(0, 0, width - 1, height - 1, TColor(255, 255, 255));
  const Box b{70, 60, width - 30, height - 70};
  drawFrame(img, b, title);
  const int lx = b.px(0.42), ly = b.py(0.05) - 20 * int(series.size());
  img.filledRectangle(lx - 8, ly - 10, b.x1 - 6, b.py(0.05) + 6, TColor(255, 255, 255));
  for (std::size_t s = 0; s < series.size(); ++s) {
    const RocSeries& r = series[s];
    if (r.fpr.size() != r.tpr.size()) {
      throw std::invalid_argument("ROC curve '" + r.label + "': fpr and tpr differ in size");
    }
    const TColor col = kColours[s % (sizeof(kColours) / sizeof(kColours[0]))];
    for (std::size_t i = 1; i < r.fpr.size(); ++i) {
      img.line(b.px(r.fpr[i - 1]), b.py(r.tpr[i - 1]), b.px(r.fpr[i]), b.py(r.tpr[i]), col, 2);
    }
    const int y = ly + 20 * int(s);
    img.line(lx, y, lx + 26, y, col, 3);
    img.textOut(lx + 34, y - 7, r.label + mrpt::format("  AUC %.3f", r.auc), TColor(30, 30, 30));
  }
  writePngAtomically(img, png);
}

}  // namespace upd::nav
