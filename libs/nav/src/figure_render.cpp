// The 3D figure: a scored cloud as coloured points (and normals as short segments) rendered
// off-screen by CFBORender, then a colour bar or legend drawn beside it with CImage primitives.
#include "upd/nav/figure.h"
#include "figure_png.h"
#include "figure_scene.h"

#include <mrpt/img/CImage.h>
#include <mrpt/opengl/CFBORender.h>
#include <mrpt/opengl/COpenGLScene.h>

#include <stdexcept>

namespace upd::nav {

namespace detail {

void renderToPng(mrpt::opengl::COpenGLScene& scene, const Frame& f, const RenderOptions& o,
                 double elevation_deg, const std::string& png) {
  if (o.width < 320 || o.height < 240 || o.width > 8192 || o.height > 8192)
    throw std::invalid_argument("figure size " + std::to_string(o.width) + "x" + std::to_string(o.height) +
                                " out of range (320x240 to 8192x8192)");
  scene.getViewport()->setCustomBackgroundColor(mrpt::img::TColorf(1, 1, 1));
  // CFBORender reads the pixels back with OpenGL's default 4-byte row alignment: an RGB row
  // of a width that is not a multiple of 4 overruns the image (heap corruption in MRPT 2.5).
  const int w3d = (o.width - kPanelWidth) / 4 * 4;
  const mrpt::opengl::CCamera cam = camera(f, o, double(w3d) / o.height, elevation_deg);
  mrpt::img::CImage view;
  try {
    mrpt::opengl::CFBORender fbo(unsigned(w3d), unsigned(o.height));
    fbo.getCamera(scene) = cam;
    fbo.render_RGB(scene, view);
  } catch (const std::exception& e) {  // MRPT's messages span lines (with a call trace)
    std::string first = e.what();
    first = first.substr(0, first.find('\n'));
    throw std::runtime_error("off-screen rendering (CFBORender, EGL) failed: " + first);
  }

  mrpt::img::CImage out(o.width, o.height, mrpt::img::CH_RGB);
  out.filledRectangle(0, 0, o.width - 1, o.height - 1, mrpt::img::TColor(255, 255, 255));
  out.drawImage(0, 0, view);
  out.line(w3d, 20, w3d, o.height - 20, mrpt::img::TColor(210, 210, 210));
  drawBar(out, o.width - kPanelWidth, o.height, o.color, f.lo.z(), f.hi.z());
  if (!o.title.empty()) {
    out.selectTextFont("10x20");
    out.textOut(16, 12, o.title, mrpt::img::TColor(20, 20, 20));
  }
  writePngAtomically(out, png);
}

}  // namespace detail

void renderFigure(const ScoredCloud& cloud, const RenderOptions& o, const std::string& png) {
  if (cloud.size() == 0) throw std::invalid_argument("nothing to render: the cloud is empty");
  const detail::Frame f = detail::upright(cloud, o.up);
  mrpt::opengl::COpenGLScene scene;
  scene.insert(detail::cloudPoints(cloud, f, o.color, o.point_size));
  if (o.normals) scene.insert(detail::normalLines(f));
  detail::renderToPng(scene, f, o, 35.0, png);
}

}  // namespace upd::nav
