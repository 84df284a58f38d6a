#include "tactile/config/calibration_file.hpp"

#include <fmt/format.h>

#include "tactile/config/yaml.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/text.hpp"

namespace tactile::config {
namespace {

// Walks "a.b[3].c" from the root to point an error at the right line; nullopt when absent.
std::optional<Node> locate(const Node& root, const std::string& path) {
  std::optional<Node> cur = root;
  std::size_t i = 0;
  while (cur && i < path.size()) {
    if (path[i] == '.') {
      ++i;
      continue;
    }
    if (path[i] == '[') {
      const std::size_t close = path.find(']', i);
      if (close == std::string::npos) return cur;
      const std::size_t index = std::stoul(path.substr(i + 1, close - i - 1));
      if (!cur->is_sequence() || index >= cur->size()) return cur;
      cur = cur->at(index);
      i = close + 1;
      continue;
    }
    std::size_t end = path.find_first_of(".[", i);
    if (end == std::string::npos) end = path.size();
    auto next = cur->find(path.substr(i, end - i));
    if (!next) return cur;
    cur = next;
    i = end;
  }
  return cur;
}

Vec2 vec2(const Node& n) {
  const auto v = n.as_doubles();
  if (v.size() != 2) n.fail("must be a list of 2 numbers [x, y], has " + std::to_string(v.size()));
  return {v[0], v[1]};
}

Vec3 vec3(const Node& n) {
  const auto v = n.as_doubles();
  if (v.size() != 3)
    n.fail("must be a list of 3 numbers [x, y, z], has " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

// A calibration is a data file meant to cross versions: a key a later version added is warned
// about (with the closest known key, for a typo) and skipped, not refused.
void warn_unknown(const Node& n, const std::vector<std::string>& known,
                  std::vector<std::string>* warnings) {
  if (!warnings) return;
  for (auto& w : n.unknown_key_warnings(known))
    warnings->push_back(std::move(w));
}

int int_in(const Node& n, std::int64_t lo, std::int64_t hi) {
  const std::int64_t v = n.as_int();
  if (v < lo || v > hi)
    n.fail("must be " + std::to_string(lo) + ".." + std::to_string(hi) + ", is " + n.text());
  return static_cast<int>(v);
}

std::string list(std::span<const double> v) {
  return fmt::format("[{}]", fmt::join(v, ", "));
}

}  // namespace

Calibration parse_calibration(const std::string& text, const std::string& source,
                              std::vector<std::string>* warnings) {
  const Node root = parse_yaml(text, source);
  if (!root.is_map()) root.fail("a calibration file must be a YAML mapping");
  warn_unknown(root,
               {"format", "sensor_id", "image", "mm_per_px", "noise_floor", "contact",
                "normal_curve", "shear_curve", "elements"},
               warnings);

  const Node format = root["format"];
  if (format.as_string() != kCalibrationFormat) {
    format.fail(std::string("must be '") + kCalibrationFormat + "', is " + format.text());
  }
  Calibration cal;
  cal.sensor_id = root["sensor_id"].as_string();
  const Node image = root["image"];
  warn_unknown(image, {"width", "height", "bit_depth"}, warnings);
  cal.width = int_in(image["width"], 1, kMaxImageSide);
  cal.height = int_in(image["height"], 1, kMaxImageSide);
  cal.bit_depth = int_in(image["bit_depth"], 1, 64);
  cal.mm_per_px = root["mm_per_px"].as_double();
  cal.noise_floor = root["noise_floor"].as_double();
  const Node contact = root["contact"];
  warn_unknown(contact, {"on", "off"}, warnings);
  cal.contact_on = contact["on"].as_double();
  cal.contact_off = contact["off"].as_double();
  const Node normal = root["normal_curve"];
  warn_unknown(normal, {"G", "newton"}, warnings);
  cal.normal_curve = PiecewiseLinear(normal["G"].as_doubles(), normal["newton"].as_doubles());
  const Node shear = root["shear_curve"];
  warn_unknown(shear, {"mm", "newton"}, warnings);
  cal.shear_curve = PiecewiseLinear(shear["mm"].as_doubles(), shear["newton"].as_doubles());

  const Node elements = root["elements"];
  const std::size_t n = elements.size();
  cal.elements.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Node e = elements.at(i);
    if (!e.is_map()) e.fail("must be a mapping with id, center_px, radius_px, zero_px and normal");
    warn_unknown(e, {"id", "center_px", "radius_px", "zero_px", "normal"}, warnings);
    ElementCalibration ec;
    const Node id = e["id"];
    const std::int64_t idv = id.as_int();
    if (idv < 0 || idv > UINT32_MAX) id.fail("must be 0..4294967295, is " + id.text());
    ec.id = static_cast<std::uint32_t>(idv);
    ec.center_px = vec2(e["center_px"]);
    ec.radius_px = e["radius_px"].as_double();
    ec.zero_px = vec2(e["zero_px"]);
    ec.normal = vec3(e["normal"]);
    cal.elements.push_back(ec);
  }

  try {
    validate(cal);
  } catch (const CalibrationError& err) {
    std::string what = err.what();
    if (err.element_id()) what = "(element id " + std::to_string(*err.element_id()) + ") " + what;
    const auto at = locate(root, err.key());
    if (at && at->path() == err.key()) at->fail(what);  // names the key's line
    throw ConfigError(source + ": key '" + err.key() + "': " + what);
  }
  return cal;
}

Calibration load_calibration(const std::filesystem::path& path,
                             std::vector<std::string>* warnings) {
  std::string text;
  try {
    text = util::read_file(path);
  } catch (const std::exception& e) {
    throw ConfigError(util::one_line(e.what()));
  }
  return parse_calibration(text, path.string(), warnings);
}

std::string format_calibration(const Calibration& cal) {
  std::string out;
  auto add = [&out](const std::string& s) { out += s; };
  add(fmt::format("format: {}\n", kCalibrationFormat));
  add(fmt::format("sensor_id: {}\n", cal.sensor_id));
  add(fmt::format("image: {{width: {}, height: {}, bit_depth: {}}}\n", cal.width, cal.height,
                  cal.bit_depth));
  add(fmt::format("mm_per_px: {}\n", cal.mm_per_px));
  add(fmt::format("noise_floor: {}\n", cal.noise_floor));
  add(fmt::format("contact: {{on: {}, off: {}}}\n", cal.contact_on, cal.contact_off));
  add("normal_curve:\n");
  add(fmt::format("  G: {}\n", list(cal.normal_curve.x())));
  add(fmt::format("  newton: {}\n", list(cal.normal_curve.y())));
  add("shear_curve:\n");
  add(fmt::format("  mm: {}\n", list(cal.shear_curve.x())));
  add(fmt::format("  newton: {}\n", list(cal.shear_curve.y())));
  add("elements:\n");
  for (const ElementCalibration& e : cal.elements) {
    add(fmt::format("  - id: {}\n", e.id));
    add(fmt::format("    center_px: [{}, {}]\n", e.center_px.x, e.center_px.y));
    add(fmt::format("    radius_px: {}\n", e.radius_px));
    add(fmt::format("    zero_px: [{}, {}]\n", e.zero_px.x, e.zero_px.y));
    add(fmt::format("    normal: [{}, {}, {}]\n", e.normal.x, e.normal.y, e.normal.z));
  }
  return out;
}

void save_calibration(const std::filesystem::path& path, const Calibration& cal) {
  validate(cal);
  util::write_file_atomic(path, format_calibration(cal));
}

}  // namespace tactile::config
