#pragma once

#include <cstdint>

namespace tactile {

// What the measurement found for one sensing element in one frame (docs/calibration.md).
// Out of contact: contact is false, G is still the measured value, and the centroid,
// displacements and forces are all 0.
struct ElementReading {
  std::uint32_t id = 0;
  bool contact = false;
  // Contact in this frame and in the previous whole frame: dx_mm and dy_mm are measured.
  bool has_displacement = false;
  double G = 0;      // integrated gray-scale value, gray levels
  double x_px = 0;   // centroid x_G (column), pixels
  double y_px = 0;   // centroid y_G (row), pixels
  double dx_mm = 0;  // eq. 5, scaled to one nominal frame period
  double dy_mm = 0;  // eq. 6, scaled to one nominal frame period
  double ux_mm = 0;  // shear displacement from zero_px (eq. 1)
  double uy_mm = 0;
  double fx = 0;  // F_x = f(u_x), newtons (eq. 2)
  double fy = 0;  // F_y = f(u_y)
  double fz = 0;  // F_z = g(G)
};

}  // namespace tactile
