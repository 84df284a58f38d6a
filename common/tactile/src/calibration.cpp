#include "tactile/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "disk.hpp"

namespace tactile {
namespace {

std::string element_key(std::size_t index, const char* field) {
  return "elements[" + std::to_string(index) + "]." + field;
}

std::string fmt_num(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

void require(bool ok, const std::string& key, std::optional<std::uint32_t> id,
             const std::string& what) {
  if (!ok) throw CalibrationError(key, id, what);
}

bool finite(double v) {
  return std::isfinite(v);
}

void check_curve(const PiecewiseLinear& c, const std::string& name, const char* xname,
                 const char* yname) {
  const auto x = c.x();
  const auto y = c.y();
  const std::string xkey = name + "." + xname;
  const std::string ykey = name + "." + yname;
  require(x.size() >= 2, xkey, std::nullopt,
          "needs at least 2 knots, has " + std::to_string(x.size()));
  require(x.size() == y.size(), ykey, std::nullopt,
          "has " + std::to_string(y.size()) + " values but " + xkey + " has " +
              std::to_string(x.size()));
  for (std::size_t i = 0; i < x.size(); ++i) {
    require(finite(x[i]), xkey + "[" + std::to_string(i) + "]", std::nullopt,
            "is not a finite number");
    require(finite(y[i]), ykey + "[" + std::to_string(i) + "]", std::nullopt,
            "is not a finite number");
  }
  require(x[0] == 0.0, xkey + "[0]", std::nullopt, "must be 0, is " + fmt_num(x[0]));
  require(y[0] == 0.0, ykey + "[0]", std::nullopt, "must be 0, is " + fmt_num(y[0]));
  for (std::size_t i = 1; i < x.size(); ++i) {
    require(x[i] > x[i - 1], xkey + "[" + std::to_string(i) + "]", std::nullopt,
            "must be strictly increasing: " + fmt_num(x[i]) + " follows " + fmt_num(x[i - 1]));
    require(y[i] >= y[i - 1], ykey + "[" + std::to_string(i) + "]", std::nullopt,
            "must be non-decreasing: " + fmt_num(y[i]) + " follows " + fmt_num(y[i - 1]));
  }
}

}  // namespace

CalibrationError::CalibrationError(std::string key, std::optional<std::uint32_t> element_id,
                                   const std::string& what)
    : std::runtime_error(what), key_(std::move(key)), element_id_(element_id) {}

std::int64_t disk_pixel_count(Vec2 center, double radius) {
  std::int64_t n = 0;
  for_each_disk_row(center, radius, [&](int, int x0, int x1) { n += x1 - x0; });
  return n;
}

std::vector<DiskRow> disk_rows(Vec2 center, double radius) {
  std::vector<DiskRow> rows;
  for_each_disk_row(center, radius, [&](int y, int x0, int x1) { rows.push_back({y, x0, x1}); });
  return rows;
}

namespace {

// [start, start + len) covering [lo, hi) with start a multiple of `offset_step` and len a
// multiple of `size_step`, inside [0, n); the whole [0, n) when the steps cannot be met.
std::pair<int, int> aligned_cover(int lo, int hi, int n, int offset_step, int size_step) {
  int start = lo / offset_step * offset_step;
  int len = (hi - start + size_step - 1) / size_step * size_step;
  if (start + len > n) {
    start = (n - len) / offset_step * offset_step;
    if (n - len < 0 || start > lo || start + len < hi) return {0, n};
  }
  return {start, len};
}

}  // namespace

Region align_region(const Region& needed, const RegionRules& rules, int image_width,
                    int image_height) {
  if (rules.offset_x_step < 1 || rules.offset_y_step < 1 || rules.width_step < 1 ||
      rules.height_step < 1) {
    throw std::invalid_argument("align_region: every step must be at least 1");
  }
  if (image_width < 1 || image_height < 1 || needed.width < 1 || needed.height < 1 ||
      needed.x < 0 || needed.y < 0 || needed.x + needed.width > image_width ||
      needed.y + needed.height > image_height) {
    throw std::invalid_argument("align_region: the region must be non-empty and inside the image");
  }
  const auto [x, w] = rules.full_width
                          ? std::pair<int, int>{0, image_width}
                          : aligned_cover(needed.x, needed.x + needed.width, image_width,
                                          rules.offset_x_step, rules.width_step);
  const auto [y, h] = aligned_cover(needed.y, needed.y + needed.height, image_height,
                                    rules.offset_y_step, rules.height_step);
  return {x, y, w, h};
}

Region region_of_interest(const Calibration& cal, RegionRules rules) {
  validate(cal);
  int x_lo = cal.width;
  int x_hi = 0;
  int y_lo = cal.height;
  int y_hi = 0;
  for (const ElementCalibration& e : cal.elements) {
    for_each_disk_row(e.center_px, e.radius_px, [&](int y, int x0, int x1) {
      x_lo = std::min(x_lo, x0);
      x_hi = std::max(x_hi, x1);
      y_lo = std::min(y_lo, y);
      y_hi = std::max(y_hi, y + 1);
    });
  }
  if (x_hi <= x_lo || y_hi <= y_lo)
    return align_region({0, 0, cal.width, cal.height}, rules, cal.width, cal.height);
  return align_region({x_lo, y_lo, x_hi - x_lo, y_hi - y_lo}, rules, cal.width, cal.height);
}

void validate(const Calibration& cal) {
  require(!cal.sensor_id.empty(), "sensor_id", std::nullopt, "must not be empty");
  require(cal.width > 0 && cal.width <= kMaxImageSide, "image.width", std::nullopt,
          "must be 1.." + std::to_string(kMaxImageSide) + ", is " + std::to_string(cal.width));
  require(cal.height > 0 && cal.height <= kMaxImageSide, "image.height", std::nullopt,
          "must be 1.." + std::to_string(kMaxImageSide) + ", is " + std::to_string(cal.height));
  require(cal.bit_depth == 8 || cal.bit_depth == 16, "image.bit_depth", std::nullopt,
          "must be 8 or 16, is " + std::to_string(cal.bit_depth));
  require(finite(cal.mm_per_px) && cal.mm_per_px > 0, "mm_per_px", std::nullopt,
          "must be a positive number, is " + fmt_num(cal.mm_per_px));
  const double max_gray = cal.bit_depth == 8 ? 255.0 : 65535.0;
  require(finite(cal.noise_floor) && cal.noise_floor >= 0 && cal.noise_floor <= max_gray,
          "noise_floor", std::nullopt,
          "must be between 0 and " + fmt_num(max_gray) + ", is " + fmt_num(cal.noise_floor));
  require(finite(cal.contact_on) && cal.contact_on > 0, "contact.on", std::nullopt,
          "must be a positive number, is " + fmt_num(cal.contact_on));
  require(finite(cal.contact_off) && cal.contact_off >= 0 && cal.contact_off <= cal.contact_on,
          "contact.off", std::nullopt,
          "must be between 0 and contact.on (" + fmt_num(cal.contact_on) + "), is " +
              fmt_num(cal.contact_off));
  check_curve(cal.normal_curve, "normal_curve", "G", "newton");
  check_curve(cal.shear_curve, "shear_curve", "mm", "newton");
  require(!cal.elements.empty(), "elements", std::nullopt, "must list at least one element");

  std::set<std::uint32_t> ids;
  for (std::size_t i = 0; i < cal.elements.size(); ++i) {
    const ElementCalibration& e = cal.elements[i];
    require(ids.insert(e.id).second, element_key(i, "id"), e.id,
            "repeats id " + std::to_string(e.id) + " of an earlier element");
    require(finite(e.center_px.x) && finite(e.center_px.y), element_key(i, "center_px"), e.id,
            "must be two finite numbers");
    require(finite(e.radius_px) && e.radius_px >= 0 && e.radius_px <= kMaxRadiusPx,
            element_key(i, "radius_px"), e.id,
            "must be between 0 and " + fmt_num(kMaxRadiusPx) + ", is " + fmt_num(e.radius_px));
    // The whole disk must lie on the sensor: inside the pixel area [-0.5, W-0.5] x [-0.5, H-0.5].
    const bool inside =
        e.center_px.x - e.radius_px >= -0.5 && e.center_px.x + e.radius_px <= cal.width - 0.5 &&
        e.center_px.y - e.radius_px >= -0.5 && e.center_px.y + e.radius_px <= cal.height - 0.5;
    require(inside, element_key(i, "center_px"), e.id,
            "disk at (" + fmt_num(e.center_px.x) + ", " + fmt_num(e.center_px.y) + ") radius " +
                fmt_num(e.radius_px) + " reaches outside the " + std::to_string(cal.width) + "x" +
                std::to_string(cal.height) + " image");
    require(disk_pixel_count(e.center_px, e.radius_px) > 0, element_key(i, "radius_px"), e.id,
            "disk of radius " + fmt_num(e.radius_px) + " holds no pixel centre");
    require(finite(e.zero_px.x) && finite(e.zero_px.y), element_key(i, "zero_px"), e.id,
            "must be two finite numbers");
    require(norm(e.zero_px - e.center_px) <= e.radius_px, element_key(i, "zero_px"), e.id,
            "(" + fmt_num(e.zero_px.x) + ", " + fmt_num(e.zero_px.y) +
                ") lies outside the element's disk");
    require(is_finite(e.normal) && std::abs(norm(e.normal) - 1.0) <= 1e-3, element_key(i, "normal"),
            e.id, "must be a unit vector, has length " + fmt_num(norm(e.normal)));
  }
}

}  // namespace tactile
