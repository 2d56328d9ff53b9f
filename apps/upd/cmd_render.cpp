// `upd render`: a scored cloud (or a raw cloud scored on the fly) drawn headless to a PNG,
// coloured by zeta, label, cost, slope or height, with a colour bar.
#include "cli.h"
#include "commands.h"
#include "view_input.h"

#include "upd/nav/figure.h"

#include <cstdio>
#include <regex>
#include <stdexcept>

namespace upd::app {

const char* const kRenderUsage =
    "usage: upd render INPUT --output FILE.png [options]\n"
    "  Draws INPUT, a scored PLY (upd analyze --output) or a raw cloud (.pcd, .ply, .xyz,\n"
    "  scored here with the default parameters), as a PNG with a colour bar. INPUT may also be\n"
    "  a playback output folder (its map, the robot's path and the robot, and the last\n"
    "  frames/NNNNNN.ply when present) or an .ot tree (its voxels). Runs headless\n"
    "  (MRPT's off-screen renderer through EGL; no display needed). See docs/FIGURES.md.\n\n"
    "options:\n"
    "  --output FILE.png     the image (required)\n"
    "  --color C             zeta (default: green = plane, blue = discontinuity, zeta from 1\n"
    "                        down to sqrt(2)/2), label, cost, slope (0-45 deg), height or\n"
    "                        rgb (the cloud's own colour); a map without zeta (map.ot)\n"
    "                        is drawn by label unless asked otherwise\n"
    "  --normals             draw normals as short dark segments (at most ~1500)\n"
    "  --view-from X,Y,Z     camera position in the cloud frame (default: 35 deg above the\n"
    "                        cloud's centre, behind (-x) and to the side, or from the diagonal\n"
    "                        that sees the front of most surfaces; far enough to see it all)\n"
    "  --look-at X,Y,Z       the point the camera looks at (default: the cloud's centre)\n"
    "  --up X,Y,Z            the cloud's up vector (default 0,0,1; 0,-1,0 for a level camera's\n"
    "                        optical frame): the view is drawn upright, a raw cloud scored with it\n"
    "  --map grid|octree|none  a folder's map: the grid as a texture (default), the tree's\n"
    "                        occupied voxels, or none (the path and the last frame only)\n"
    "  --size WxH            image size in pixels (default 1280x900)\n"
    "  --title TEXT          caption at the top left (default: INPUT and the colouring)\n";

namespace {

std::string baseName(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace

std::pair<int, int> parseImageSize(const std::string& s) {
  static const std::regex re("([0-9]{1,5})x([0-9]{1,5})");
  std::smatch m;
  if (!std::regex_match(s, m, re)) throw UsageError("--size '" + s + "': expected WxH, e.g. 1280x900");
  return {std::stoi(m[1]), std::stoi(m[2])};
}

int runRender(const std::vector<std::string>& argv) {
  const Args args(argv, {"--output", "--color", "--view-from", "--look-at", "--up", "--size", "--title", "--map"},
                  {"--normals"});
  if (args.positionals().size() != 1) throw UsageError("expected exactly one INPUT file");
  const std::string input = args.positionals()[0];
  const auto output = args.str("--output");
  if (!output) throw UsageError("--output FILE.png is required");
  nav::RenderOptions opt;
  const auto asked_color = args.str("--color");
  try {
    if (asked_color) nav::parseFigureColor(*asked_color);  // a bad name fails before the input
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--color: ") + e.what());
  }
  opt.normals = args.flag("--normals");
  opt.view_from = args.vector3("--view-from");
  opt.look_at = args.vector3("--look-at");
  if (const auto up = args.vector3("--up")) opt.up = *up;
  if (!(opt.up.norm() > 0)) throw UsageError("--up must not be the zero vector");
  if (const auto size = args.str("--size")) std::tie(opt.width, opt.height) = parseImageSize(*size);

  nav::MapStyle style = nav::MapStyle::Grid;
  try {
    style = nav::parseMapStyle(args.str("--map").value_or("grid"));
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--map: ") + e.what());
  }
  const ViewInput in = readViewInput(input, opt.up);
  const std::string color = firstColor(in, asked_color);
  opt.color = nav::parseFigureColor(color);
  opt.title = args.str("--title").value_or(baseName(input) + ": " + color);
  if (!in.is_map) {
    nav::renderFigure(*in.cloud, opt, *output);
    std::printf("%s: %zu points drawn by %s to %s (%dx%d)\n", input.c_str(), in.cloud->size(), color.c_str(),
                output->c_str(), opt.width, opt.height);
    return 0;
  }
  nav::renderMapFigure(in.map, firstMapStyle(in, style), in.cloud ? &*in.cloud : nullptr, opt, *output);
  std::printf("%s: map (%d x %d cells, %zu voxels, %zu path points%s) drawn by %s to %s (%dx%d)\n",
              input.c_str(), in.map.nx, in.map.ny, in.map.voxels.size(), in.map.path.size(),
              in.cloud ? (", " + baseName(in.cloud_file)).c_str() : "", color.c_str(), output->c_str(),
              opt.width, opt.height);
  return 0;
}

}  // namespace upd::app
