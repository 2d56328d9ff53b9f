// Constants shared by the terrain's source files (terrain.cpp: heights and truth;
// terrain_raycast.cpp: ray casting; terrain_sampling.cpp: surface samples). Private to libs/sim.
#pragma once

namespace upd::sim::terrain_detail {

constexpr double kPi = 3.14159265358979323846;
// Offset across an edge to read the height on either side of it [m]: far below any feature
// size, far above the rounding of rotated coordinates.
constexpr double kAcross_m = 1e-6;

}  // namespace upd::sim::terrain_detail
