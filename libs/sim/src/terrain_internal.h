// Constants shared by the terrain's source files (terrain.cpp: heights and truth;
// terrain_raycast.cpp: ray casting; terrain_sampling.cpp: surface samples). Private to libs/sim.
#pragma once

namespace upd::sim::terrain_detail {

constexpr double kPi = 3.14159265358979323846;
// Offset across an edge to read the height on either side of it [m]: far below any feature
// size, far above the rounding of rotated coordinates.
constexpr double kAcross_m = 1e-6;

// sin(x) for |x| < 1e6 without a library call, to within a few ulp of std::sin: the argument
// reduced by multiples of pi/2 (Cody-Waite: pi/2 as 33 leading bits, exact in the product, and
// the rest) to |r| <= pi/4, then the
// Taylor series of sin or cos of r (degrees 15 and 16: the first term left out is below 1e-17)
// chosen by the quadrant. The roughness evaluates 8 waves per height: std::sin was most of the
// cost of rendering a frame.
inline double fastSin(double x) {
  constexpr double kTwoOverPi = 0.63661977236758134308;
  constexpr double kPio2Hi = 1.57079632673412561417e+00;  // the first 33 bits of pi/2
  constexpr double kPio2Lo = 6.07710050650619224932e-11;  // pi/2 - kPio2Hi
  constexpr double kRound = 6755399441055744.0;           // 1.5 x 2^52: adding it rounds
  const double qd = (x * kTwoOverPi + kRound) - kRound;   // to the nearest whole number
  const double r = (x - qd * kPio2Hi) - qd * kPio2Lo;
  const double z = r * r;
  const double s =
      r + r * z * (-1.0 / 6 + z * (1.0 / 120 + z * (-1.0 / 5040 + z * (1.0 / 362880 +
                   z * (-1.0 / 39916800 + z * (1.0 / 6227020800.0 +
                   z * (-1.0 / 1307674368000.0)))))));
  const double c =
      1.0 + z * (-0.5 + z * (1.0 / 24 + z * (-1.0 / 720 + z * (1.0 / 40320 +
                 z * (-1.0 / 3628800 + z * (1.0 / 479001600.0 +
                 z * (-1.0 / 87178291200.0 + z * (1.0 / 20922789888000.0))))))));
  const auto q = static_cast<long long>(qd);
  const double v = (q & 1) ? c : s;
  return (q & 2) ? -v : v;
}

}  // namespace upd::sim::terrain_detail
