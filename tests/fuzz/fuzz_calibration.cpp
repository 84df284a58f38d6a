// libFuzzer target: the calibration loader (common/config parse_calibration) on any text. A
// refusal must be a ConfigError; an accepted calibration must pass tactile::validate and survive
// format_calibration -> parse_calibration unchanged (the loader promises parse(format(c)) == c).
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "tactile/config/calibration_file.hpp"
#include "tactile/config/yaml.hpp"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

bool same_curve(const tactile::PiecewiseLinear& a, const tactile::PiecewiseLinear& b) {
  return std::equal(a.x().begin(), a.x().end(), b.x().begin(), b.x().end()) &&
         std::equal(a.y().begin(), a.y().end(), b.y().begin(), b.y().end());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  tactile::Calibration cal;
  try {
    cal = tactile::config::parse_calibration(text, "fuzz.yaml");
  } catch (const tactile::config::ConfigError&) {
    return 0;
  }
  tactile::validate(cal);  // throws (and so crashes the fuzzer) if the loader let a bad one by
  const tactile::Calibration again =
      tactile::config::parse_calibration(tactile::config::format_calibration(cal), "again.yaml");
  check(again.sensor_id == cal.sensor_id && again.width == cal.width &&
        again.height == cal.height && again.bit_depth == cal.bit_depth &&
        again.mm_per_px == cal.mm_per_px && again.noise_floor == cal.noise_floor &&
        again.contact_on == cal.contact_on && again.contact_off == cal.contact_off);
  check(same_curve(again.normal_curve, cal.normal_curve) &&
        same_curve(again.shear_curve, cal.shear_curve));
  check(again.elements.size() == cal.elements.size());
  for (std::size_t i = 0; i < cal.elements.size(); ++i) {
    const auto& a = again.elements[i];
    const auto& b = cal.elements[i];
    check(a.id == b.id && a.center_px.x == b.center_px.x && a.center_px.y == b.center_px.y &&
          a.radius_px == b.radius_px && a.zero_px.x == b.zero_px.x && a.zero_px.y == b.zero_px.y &&
          a.normal.x == b.normal.x && a.normal.y == b.normal.y && a.normal.z == b.normal.z);
  }
  return 0;
}
