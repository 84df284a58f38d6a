#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactile/curve.hpp"
#include "tactile/geometry.hpp"

namespace tactile {

inline constexpr const char* kCalibrationFormat = "tactile-calibration/1";

// Limits that keep every integer sum of the measurement exact in 64 bits (docs/calibration.md).
inline constexpr int kMaxImageSide = 16384;
inline constexpr double kMaxRadiusPx = 1024.0;

struct ElementCalibration {
  std::uint32_t id = 0;
  Vec2 center_px;        // centre of the measurement disk S
  double radius_px = 0;  // a pixel belongs to S when its centre is at most this far away
  Vec2 zero_px;          // centroid under pure normal load
  Vec3 normal{0, 0, 1};  // unit inward normal in the fingertip frame
};

// One sensor's calibration: docs/calibration.md, "The calibration file".
struct Calibration {
  std::string sensor_id;
  int width = 0;
  int height = 0;
  int bit_depth = 8;
  double mm_per_px = 0;
  double noise_floor = 0;        // gray levels subtracted from every increment before weighting
  double contact_on = 0;         // G at which an element enters contact
  double contact_off = 0;        // G below which it leaves contact
  PiecewiseLinear normal_curve;  // F_z = g(G), G in gray levels, newtons
  PiecewiseLinear shear_curve;   // F = f(u), u in mm, newtons (odd extension for u < 0)
  std::vector<ElementCalibration> elements;
};

// A calibration that breaks a rule. key() names the offending key as a path
// ("elements[3].radius_px", "normal_curve.G"); element_id() names the element where there is one.
class CalibrationError : public std::runtime_error {
 public:
  CalibrationError(std::string key, std::optional<std::uint32_t> element_id,
                   const std::string& what);
  const std::string& key() const { return key_; }
  std::optional<std::uint32_t> element_id() const { return element_id_; }

 private:
  std::string key_;
  std::optional<std::uint32_t> element_id_;
};

// Checks every rule of docs/calibration.md ("Rules") that does not concern the file's syntax;
// throws CalibrationError for the first rule broken.
void validate(const Calibration& cal);

// Number of pixels whose centres lie in the disk (the size of S).
std::int64_t disk_pixel_count(Vec2 center, double radius);

// One image row of a disk: the pixels (x, y) with x0 <= x < x1 have their centres in it.
struct DiskRow {
  std::int32_t y;
  std::int32_t x0;
  std::int32_t x1;
};
// The rows of the disk S, top to bottom (not clipped to any image).
std::vector<DiskRow> disk_rows(Vec2 center, double radius);

// A rectangle of the sensor's image, in pixels.
struct Region {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
  friend bool operator==(const Region&, const Region&) = default;
};

// What a camera's region of interest must obey (GenICam OffsetX/OffsetY/Width/Height
// increments); full_width keeps whole rows, for cameras that can only skip rows.
struct RegionRules {
  int offset_x_step = 1;
  int offset_y_step = 1;
  int width_step = 1;
  int height_step = 1;
  bool full_width = false;
};

// The smallest region that holds every pixel of every element's disk and obeys the rules:
// offsets multiples of their steps, sizes multiples of theirs, inside the image (where the
// steps cannot all be met inside the image, the side falls back to the whole image). Set the
// camera to it and hand the extractor views with origin_x = x, origin_y = y: the measurement
// is the same as on whole frames, with fewer rows to transfer and read (docs/benchmarks.md).
// Throws CalibrationError for an invalid calibration, std::invalid_argument for steps < 1.
Region region_of_interest(const Calibration& cal, RegionRules rules = {});

// The smallest region that holds `needed` and obeys `rules` inside an image_width x image_height
// sensor (the whole side where the steps cannot be met). region_of_interest() is this on the
// disks' bounding box; a camera applies it with its own steps. Throws std::invalid_argument for
// steps < 1 or a `needed` that is empty or not inside the image.
Region align_region(const Region& needed, const RegionRules& rules, int image_width,
                    int image_height);

}  // namespace tactile
