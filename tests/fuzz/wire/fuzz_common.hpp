#pragma once

// What the wire fuzz targets and their seed generator share: the fixed calibration TactileFrames
// are read against, the fingertip ids of the arm link, and the harness's way to report a broken
// promise (abort, so libFuzzer saves the input).
#include <cstdio>
#include <cstdlib>
#include <string>

#include "tactile/calibration.hpp"
#include "tactile/wire/arm.hpp"

namespace tactile::fuzz {

// Five elements: few enough that mutations reach "exactly the calibration's elements".
inline Calibration wire_calibration(const std::string& sensor_id = "left") {
  Calibration cal;
  cal.sensor_id = sensor_id;
  cal.width = 160;
  cal.height = 120;
  cal.bit_depth = 8;
  cal.mm_per_px = 0.025;
  cal.noise_floor = 4;
  cal.contact_on = 400;
  cal.contact_off = 250;
  cal.normal_curve = PiecewiseLinear({0, 2000, 8000, 20000}, {0, 0.2, 1.0, 3.0});
  cal.shear_curve = PiecewiseLinear({0, 0.02, 0.08}, {0, 0.05, 0.4});
  const double xs[] = {80, 50, 110, 80, 80};
  const double ys[] = {60, 60, 60, 30, 90};
  for (std::uint32_t i = 0; i < 5; ++i) {
    ElementCalibration e;
    e.id = 10 + i;  // not 0..4, so an id check means something
    e.center_px = {xs[i], ys[i]};
    e.radius_px = 12;
    e.zero_px = e.center_px;
    cal.elements.push_back(e);
  }
  return cal;
}

inline const wire::FingertipIds kFingertipIds{"left", "right"};

// A promise of the code under test is broken: say which, and abort (libFuzzer keeps the input).
inline void require(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "broken promise: %s\n", what);
  std::abort();
}

}  // namespace tactile::fuzz
