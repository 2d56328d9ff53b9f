// The robot config on arbitrary text, loaded as `upd` loads it: every section read and
// validated, then the unknown keys checked. Any input must load or throw std::exception.
#include "fuzz_input.h"

#include "upd/mrpt_bridge/robot_config.h"

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = upd::fuzz::inputPath(".ini");
  upd::fuzz::writeInput(path, data, size);
  try {
    upd::core::PipelineParams pipeline;
    upd::core::BaselineParams baseline;
    upd::mrpt_bridge::SourceParams source;
    upd::maps::GridParams grid;
    upd::maps::FusionParams fusion;
    upd::maps::OctreeParams octree;
    upd::mrpt_bridge::GroundTruthParams ground_truth;
    upd::mrpt_bridge::SimulationParams simulation;
    upd::mrpt_bridge::RobotConfigParts parts;
    parts.pipeline = &pipeline;
    parts.baseline = &baseline;
    parts.source = &source;
    parts.grid = &grid;
    parts.fusion = &fusion;
    parts.octree = &octree;
    parts.ground_truth = &ground_truth;
    parts.simulation = &simulation;
    upd::mrpt_bridge::IniReader ini(path);
    upd::mrpt_bridge::readRobotConfig(ini, parts);
    ini.checkAllKeysKnown();
  } catch (const std::exception&) {
    // a refused config
  }
  return 0;
}
