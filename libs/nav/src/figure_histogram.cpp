// The distribution of zeta at several d_m as a line plot drawn with CImage primitives: the
// share of points per bin, one line with markers per d_m, axes with ticks, labels and a legend.
#include "upd/nav/figure.h"
#include "figure_png.h"

#include <mrpt/core/format.h>
#include <mrpt/img/CImage.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace upd::nav {
namespace {

using mrpt::img::TColor;

const TColor kPalette[] = {TColor(30, 90, 200), TColor(225, 110, 20), TColor(40, 160, 70),
                           TColor(200, 40, 40), TColor(130, 60, 170), TColor(90, 90, 90)};

struct Plot {
  int x0, y0, x1, y1;  // the plot area (y0 top)
  double lo, hi, ymax;
  int px(double v) const { return x0 + int(std::lround((v - lo) / (hi - lo) * (x1 - x0))); }
  int py(double pct) const { return y1 - int(std::lround(pct / ymax * (y1 - y0))); }
};

std::vector<double> shares(const ZetaSeries& s, double lo, double hi, int bins, const std::string& name) {
  std::vector<double> count(std::size_t(bins), 0.0);
  std::size_t n = 0;
  for (float z : s.zeta) {
    if (!std::isfinite(z)) continue;
    const int b = std::clamp(int((z - lo) / (hi - lo) * bins), 0, bins - 1);
    count[std::size_t(b)] += 1;
    ++n;
  }
  if (n == 0) throw std::invalid_argument(name + ": no finite zeta to plot");
  for (auto& c : count) c *= 100.0 / double(n);
  return count;
}

double niceStep(double range) {  // 1, 2 or 5 times a power of ten, about 5 ticks over range
  const double raw = range / 5.0, p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0}) if (m * p >= raw) return m * p;
  return 10 * p;
}

void drawAxes(mrpt::img::CImage& img, const Plot& p) {
  const TColor grid(225, 225, 225), ink(40, 40, 40);
  img.selectTextFont("9x15");
  const double ystep = niceStep(p.ymax);
  for (double v = 0; v <= p.ymax + 1e-9; v += ystep) {
    img.line(p.x0, p.py(v), p.x1, p.py(v), grid);
    img.line(p.x0 - 6, p.py(v), p.x0, p.py(v), ink);
    const std::string t = mrpt::format("%g", v);
    img.textOut(p.x0 - 12 - 9 * int(t.size()), p.py(v) - 7, t, ink);
  }
  for (int k = 0; p.lo + 0.05 * k <= p.hi + 1e-9; ++k) {
    const double v = p.lo + 0.05 * k;
    img.line(p.px(v), p.y0, p.px(v), p.y1, grid);
    img.line(p.px(v), p.y1, p.px(v), p.y1 + 6, ink);
    img.textOut(p.px(v) - 18, p.y1 + 12, mrpt::format("%.2f", v), ink);
  }
  img.rectangle(p.x0, p.y0, p.x1, p.y1, ink);
  img.textOut((p.x0 + p.x1) / 2 - 100, p.y1 + 36, "zeta (1 = plane, 0.71 = right angle)", ink);
  img.textOut(p.x0 - 50, p.y0 - 24, "share of points [%]", ink);
}

void drawSeries(mrpt::img::CImage& img, const Plot& p, const std::vector<double>& pct, TColor col) {
  const int bins = int(pct.size());
  const double w = (p.hi - p.lo) / bins;
  int px_prev = 0, py_prev = 0;
  for (int b = 0; b < bins; ++b) {
    const int x = p.px(p.lo + (b + 0.5) * w), y = p.py(pct[std::size_t(b)]);
    if (b > 0) img.line(px_prev, py_prev, x, y, col, 2);
    img.filledRectangle(x - 3, y - 3, x + 3, y + 3, col);
    px_prev = x;
    py_prev = y;
  }
}

void drawLegend(mrpt::img::CImage& img, const Plot& p, const std::vector<ZetaSeries>& series) {
  const int x = p.x0 + 16, y = p.y0 + 14, h = 22 * int(series.size()) + 10;
  img.filledRectangle(x, y, x + 150, y + h, TColor(255, 255, 255));
  img.rectangle(x, y, x + 150, y + h, TColor(170, 170, 170));
  for (std::size_t i = 0; i < series.size(); ++i) {
    const TColor col = kPalette[i % (sizeof(kPalette) / sizeof(kPalette[0]))];
    const int yy = y + 16 + 22 * int(i);
    img.line(x + 10, yy, x + 40, yy, col, 2);
    img.filledRectangle(x + 22, yy - 3, x + 28, yy + 3, col);
    img.textOut(x + 50, yy - 7, mrpt::format("d_m = %g m", series[i].radius_m), TColor(30, 30, 30));
  }
}

}  // namespace

void drawZetaHistogram(const std::vector<ZetaSeries>& series, const HistogramOptions& o,
                       const std::string& png) {
  if (series.empty()) throw std::invalid_argument("no zeta series to plot");
  if (o.width < 400 || o.height < 300 || o.width > 8192 || o.height > 8192)
    throw std::invalid_argument("histogram size " + std::to_string(o.width) + "x" + std::to_string(o.height) +
                                " out of range (400x300 to 8192x8192)");
  if (o.bins < 2 || o.bins > 500) throw std::invalid_argument("histogram bins must be in 2..500");
  std::vector<float> all;
  for (const auto& s : series)
    for (float z : s.zeta) if (std::isfinite(z)) all.push_back(z);
  double zmin = 1.0;
  if (!all.empty()) {
    std::nth_element(all.begin(), all.begin() + std::ptrdiff_t(all.size() / 100), all.end());
    zmin = all[all.size() / 100];
  }
  Plot p{90, 70, o.width - 30, o.height - 80, std::min(0.70, std::floor(zmin * 20.0) / 20.0), 1.0, 1.0};
  std::vector<std::vector<double>> pct;
  for (const auto& s : series) {
    pct.push_back(shares(s, p.lo, p.hi, o.bins, mrpt::format("d_m = %g m", s.radius_m)));
    p.ymax = std::max(p.ymax, *std::max_element(pct.back().begin(), pct.back().end()));
  }
  const double step = niceStep(p.ymax * 1.08);
  p.ymax = step * std::ceil(p.ymax * 1.08 / step);

  mrpt::img::CImage img(o.width, o.height, mrpt::img::CH_RGB);
  img.filledRectangle(0, 0, o.width - 1, o.height - 1, TColor(255, 255, 255));
  drawAxes(img, p);
  for (std::size_t i = 0; i < pct.size(); ++i)
    drawSeries(img, p, pct[i], kPalette[i % (sizeof(kPalette) / sizeof(kPalette[0]))]);
  drawLegend(img, p, series);
  if (!o.title.empty()) {
    img.selectTextFont("10x20");
    img.textOut(p.x0, 16, o.title, TColor(20, 20, 20));
  }
  writePngAtomically(img, png);
}

}  // namespace upd::nav
