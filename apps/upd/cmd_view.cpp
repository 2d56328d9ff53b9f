// `upd view`: the interactive 3D viewer (upd/nav/viewer.h) on a scored PLY or raw cloud, an
// OctoMap tree (.ot) or a playback output folder.
#include "cli.h"
#include "commands.h"
#include "view_input.h"

#include "upd/nav/viewer.h"

#include <cstdio>
#include <stdexcept>

namespace upd::app {

const char* const kViewUsage =
    "usage: upd view FILE|DIR [options]\n"
    "  Opens a 3D window on FILE, a scored PLY (upd analyze --output) or a raw cloud (.pcd,\n"
    "  .ply, .xyz: scored here with the default parameters), an .ot tree (map.ot or\n"
    "  map_traversability.ot: its occupied voxels), or DIR, a playback output folder (its\n"
    "  map, the robot's path and the robot, and the last frames/NNNNNN.ply when present).\n"
    "  Needs a display (DISPLAY). See docs/VIEWER.md.\n\n"
    "keys in the window:\n"
    "  z l c s h (or 1-5)  colour by zeta, label, cost, slope, height\n"
    "  n normals on/off    m map: grid / octree / none    r reset the view\n"
    "  p save a screenshot (upd-view-NNN.png)    t help text on/off    q or Esc close\n\n"
    "options:\n"
    "  --color C             the first colouring: zeta (default; label for a map without\n"
    "                        zeta, map.ot), label, cost, slope, height\n"
    "  --normals             start with the normals shown\n"
    "  --map grid|octree|none  a folder's map drawn first (default grid)\n"
    "  --up X,Y,Z            a cloud's up vector (default 0,0,1; 0,-1,0 for a camera frame)\n"
    "  --size WxH            window size in pixels (default 1280x900)\n"
    "  --keys KEYS           keys acted on once the window shows, in order, as if typed\n"
    "  --screenshot FILE.png save the window once it shows (after --keys)\n"
    "  --exit-after          close the window after the screenshot instead of waiting\n";

int runView(const std::vector<std::string>& argv) {
  const Args args(argv, {"--color", "--map", "--up", "--size", "--keys", "--screenshot"},
                  {"--normals", "--exit-after"});
  if (args.positionals().size() != 1) throw UsageError("expected exactly one FILE or DIR");
  const std::string input = args.positionals()[0];
  nav::ViewerOptions opt;
  try {
    if (const auto c = args.str("--color")) opt.color = nav::parseFigureColor(*c);
    opt.map = nav::parseMapStyle(args.str("--map").value_or("grid"));
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  opt.normals = args.flag("--normals");
  if (const auto up = args.vector3("--up")) opt.up = *up;
  if (!(opt.up.norm() > 0)) throw UsageError("--up must not be the zero vector");
  if (const auto size = args.str("--size")) std::tie(opt.width, opt.height) = parseImageSize(*size);
  if (opt.width < 480 || opt.height < 360 || opt.width > 8192 || opt.height > 8192) {
    throw UsageError("--size: the window must be 480x360 to 8192x8192");
  }
  const auto screenshot = args.str("--screenshot");
  if (args.flag("--exit-after") && !screenshot) throw UsageError("--exit-after needs --screenshot FILE.png");

  ViewInput in = readViewInput(input, opt.up);  // a bad file fails before a window opens
  if (in.is_map) opt.up = Eigen::Vector3f::UnitZ();
  opt.color = nav::parseFigureColor(firstColor(in, args.str("--color")));
  opt.map = firstMapStyle(in, opt.map);
  opt.title = "upd view " + input;
  nav::Viewer viewer(opt);
  viewer.setContent(in.cloud ? std::move(*in.cloud) : nav::ScoredCloud{}, std::move(in.map));
  for (const char key : args.str("--keys").value_or("")) viewer.pressKey(key);
  if (screenshot) {
    viewer.saveScreenshot(*screenshot);
    std::printf("%s: window saved to %s\n", input.c_str(), screenshot->c_str());
    if (args.flag("--exit-after")) return 0;
  }
  viewer.runUntilClosed();
  return 0;
}

}  // namespace upd::app
