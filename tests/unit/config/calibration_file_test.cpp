// Every rule of the calibration file (docs/calibration.md): a file that breaks one is
// refused with a message naming the file, the key and, where there is one, the element.
#include "tactile/config/calibration_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tactile/config/yaml.hpp"

namespace tactile::config {
namespace {

const std::string kGood = R"(format: tactile-calibration/1
sensor_id: left
image: {width: 640, height: 480, bit_depth: 8}
mm_per_px: 0.025
noise_floor: 4.0
contact: {on: 400.0, off: 250.0}
normal_curve:
  G: [0, 2000, 8000, 20000]
  newton: [0, 0.2, 1.0, 3.0]
shear_curve:
  mm: [0, 0.02, 0.08]
  newton: [0, 0.05, 0.4]
elements:
  - id: 0
    center_px: [320.0, 240.0]
    radius_px: 14.0
    zero_px: [320.0, 240.0]
    normal: [0.0, 0.0, 1.0]
  - id: 1
    center_px: [360.0, 240.0]
    radius_px: 14.0
    zero_px: [360.5, 240.0]
    normal: [0.6, 0.0, 0.8]
)";

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << "test text lacks: " << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

TEST(CalibrationFile, GoodFileLoads) {
  std::vector<std::string> warnings;
  const Calibration cal = parse_calibration(kGood, "good.yaml", &warnings);
  EXPECT_TRUE(warnings.empty());
  EXPECT_EQ(cal.sensor_id, "left");
  EXPECT_EQ(cal.width, 640);
  EXPECT_EQ(cal.bit_depth, 8);
  EXPECT_DOUBLE_EQ(cal.contact_on, 400.0);
  ASSERT_EQ(cal.elements.size(), 2U);
  EXPECT_DOUBLE_EQ(cal.elements[1].zero_px.x, 360.5);
  EXPECT_DOUBLE_EQ(cal.elements[1].normal.x, 0.6);
  EXPECT_DOUBLE_EQ(cal.normal_curve(5000), 0.6);
}

TEST(CalibrationFile, RoundTripsThroughFormat) {
  const Calibration a = parse_calibration(kGood, "good.yaml");
  const Calibration b = parse_calibration(format_calibration(a), "again.yaml");
  EXPECT_EQ(format_calibration(a), format_calibration(b));
  EXPECT_EQ(b.elements[1].zero_px.x, a.elements[1].zero_px.x);
}

TEST(CalibrationFile, UnknownKeysAreWarnedAbout) {
  std::vector<std::string> warnings;
  parse_calibration(replace(kGood, "sensor_id: left", "sensor_id: left\nserial: 1234"), "w.yaml",
                    &warnings);
  ASSERT_EQ(warnings.size(), 1U);
  EXPECT_NE(warnings[0].find("w.yaml:3: unknown key 'serial' ignored"), std::string::npos)
      << warnings[0];
}

TEST(CalibrationFile, AMisspeltKeyIsWarnedAboutWithTheClosestKey) {
  std::vector<std::string> warnings;
  const Calibration c = parse_calibration(
      replace(kGood, "noise_floor:", "noise_floor: 4.0\nnoise_flor:"), "w.yaml", &warnings);
  ASSERT_EQ(warnings.size(), 1U);
  EXPECT_NE(warnings[0].find("unknown key 'noise_flor' ignored (did you mean 'noise_floor'?)"),
            std::string::npos)
      << warnings[0];
}

TEST(CalibrationFile, MissingFileNamesTheFile) {
  try {
    load_calibration("/nonexistent/cal.yaml");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/cal.yaml"), std::string::npos) << e.what();
  }
}

struct Rule {
  const char* name;
  std::string from;
  std::string to;
  std::vector<std::string> expect;  // substrings of the message besides the file name
};

class CalibrationRule : public ::testing::TestWithParam<Rule> {};

TEST_P(CalibrationRule, IsRefusedWithAMessageNamingKeyAndElement) {
  const Rule& r = GetParam();
  const std::string text = replace(kGood, r.from, r.to);
  try {
    parse_calibration(text, "sensor-left.yaml");
    FAIL() << r.name << ": accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("sensor-left.yaml", 0), 0U) << what;
    for (const std::string& s : r.expect)
      EXPECT_NE(what.find(s), std::string::npos) << "missing '" << s << "' in: " << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "not one line: " << what;
  }
}

const Rule kRules[] = {
    {"missing format", "format: tactile-calibration/1\n", "", {"'format' is missing"}},
    {"wrong format",
     "tactile-calibration/1",
     "tactile-calibration/2",
     {"'format'", "tactile-calibration/2"}},
    {"missing sensor_id", "sensor_id: left\n", "", {"'sensor_id' is missing"}},
    {"empty sensor_id", "sensor_id: left", "sensor_id: ''", {"'sensor_id'", "empty"}},
    {"missing image",
     "image: {width: 640, height: 480, bit_depth: 8}\n",
     "",
     {"'image' is missing"}},
    {"missing width", "width: 640, ", "", {"'image.width' is missing"}},
    {"zero width", "width: 640", "width: 0", {"'image.width'", "'0'"}},
    {"text width", "width: 640", "width: wide", {"'image.width'", "'wide'"}},
    {"bit depth 12", "bit_depth: 8", "bit_depth: 12", {"'image.bit_depth'", "8 or 16", "12"}},
    {"missing mm_per_px", "mm_per_px: 0.025\n", "", {"'mm_per_px' is missing"}},
    {"negative mm_per_px", "mm_per_px: 0.025", "mm_per_px: -0.025", {"'mm_per_px'", "-0.025"}},
    {"nan mm_per_px", "mm_per_px: 0.025", "mm_per_px: .nan", {"'mm_per_px'", "finite"}},
    {"missing noise_floor", "noise_floor: 4.0\n", "", {"'noise_floor' is missing"}},
    {"negative noise_floor", "noise_floor: 4.0", "noise_floor: -1", {"'noise_floor'", "-1"}},
    {"missing contact.on", "on: 400.0, ", "", {"'contact.on' is missing"}},
    {"zero contact.on", "on: 400.0", "on: 0", {"'contact.on'", "positive"}},
    {"off above on", "off: 250.0", "off: 500.0", {"'contact.off'", "500"}},
    {"missing normal_curve",
     "normal_curve:\n  G: [0, 2000, 8000, 20000]\n  newton: [0, 0.2, 1.0, 3.0]\n",
     "",
     {"'normal_curve' is missing"}},
    {"normal G not from 0",
     "G: [0, 2000",
     "G: [10, 2000",
     {"'normal_curve.G[0]'", "must be 0", "10"}},
    {"normal G not increasing",
     "G: [0, 2000, 8000, 20000]",
     "G: [0, 2000, 2000, 20000]",
     {"'normal_curve.G[2]'", "strictly increasing"}},
    {"normal newton decreasing",
     "newton: [0, 0.2, 1.0, 3.0]",
     "newton: [0, 0.2, 0.1, 3.0]",
     {"'normal_curve.newton[2]'", "non-decreasing"}},
    {"normal newton not from 0",
     "newton: [0, 0.2, 1.0, 3.0]",
     "newton: [0.1, 0.2, 1.0, 3.0]",
     {"'normal_curve.newton[0]'", "must be 0"}},
    {"normal lengths differ",
     "newton: [0, 0.2, 1.0, 3.0]",
     "newton: [0, 0.2, 1.0]",
     {"'normal_curve.newton'", "3 values", "4"}},
    {"normal one knot",
     "G: [0, 2000, 8000, 20000]\n  newton: [0, 0.2, 1.0, 3.0]",
     "G: [0]\n  newton: [0]",
     {"'normal_curve.G'", "at least 2"}},
    {"normal G not a list", "G: [0, 2000, 8000, 20000]", "G: 5", {"'normal_curve.G'", "list"}},
    {"shear mm not increasing",
     "mm: [0, 0.02, 0.08]",
     "mm: [0, 0.08, 0.02]",
     {"'shear_curve.mm[2]'", "strictly increasing"}},
    {"shear newton decreasing",
     "newton: [0, 0.05, 0.4]",
     "newton: [0, 0.5, 0.4]",
     {"'shear_curve.newton[2]'", "non-decreasing"}},
    {"missing elements", "elements:\n", "other:\n", {"'elements' is missing"}},
    {"empty elements",
     "elements:\n  - id: 0",
     "elements: []\nunused:\n  - id: 0",
     {"'elements'", "at least one"}},
    {"duplicate id", "  - id: 1\n", "  - id: 0\n", {"'elements[1].id'", "element id 0", "repeats"}},
    {"negative id", "  - id: 1\n", "  - id: -1\n", {"'elements[1].id'"}},
    {"missing center",
     "    center_px: [360.0, 240.0]\n",
     "",
     {"'elements[1].center_px' is missing"}},
    {"center one number",
     "center_px: [360.0, 240.0]",
     "center_px: [360.0]",
     {"'elements[1].center_px'", "2 numbers"}},
    {"disk outside image",
     "center_px: [360.0, 240.0]",
     "center_px: [630.0, 240.0]",
     {"'elements[1].center_px'", "element id 1", "outside", "640x480"}},
    {"disk past the top",
     "center_px: [320.0, 240.0]",
     "center_px: [320.0, 5.0]",
     {"'elements[0].center_px'", "element id 0", "outside"}},
    {"negative radius",
     "radius_px: 14.0\n    zero_px: [360.5",
     "radius_px: -3\n    zero_px: [360.5",
     {"'elements[1].radius_px'", "element id 1", "-3"}},
    {"radius too large",
     "radius_px: 14.0\n    zero_px: [360.5",
     "radius_px: 2000\n    zero_px: [360.5",
     {"'elements[1].radius_px'", "element id 1", "1024"}},
    {"empty disk",
     "center_px: [360.0, 240.0]\n    radius_px: 14.0",
     "center_px: [360.5, 240.5]\n    radius_px: 0.2",
     {"'elements[1].radius_px'", "element id 1", "no pixel"}},
    {"zero outside disk",
     "zero_px: [360.5, 240.0]",
     "zero_px: [380.0, 240.0]",
     {"'elements[1].zero_px'", "element id 1", "outside"}},
    {"normal not unit",
     "normal: [0.6, 0.0, 0.8]",
     "normal: [0.6, 0.0, 0.9]",
     {"'elements[1].normal'", "element id 1", "unit"}},
    {"normal two numbers",
     "normal: [0.6, 0.0, 0.8]",
     "normal: [0.6, 0.8]",
     {"'elements[1].normal'", "3 numbers"}},
    {"not yaml", "elements:", "elements: [", {"not valid YAML"}},
};

INSTANTIATE_TEST_SUITE_P(Rules, CalibrationRule, ::testing::ValuesIn(kRules),
                         [](const ::testing::TestParamInfo<Rule>& p) {
                           std::string n = p.param.name;
                           for (char& c : n) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return n;
                         });

TEST(CalibrationFile, ErrorNamesTheLine) {
  try {
    parse_calibration(replace(kGood, "normal: [0.6, 0.0, 0.8]", "normal: [0.6, 0.0, 0.9]"),
                      "l.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("l.yaml:23:", 0), 0U) << e.what();
  }
}

TEST(CalibrationFile, SaveWritesAtomicallyAndRefusesInvalid) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("calib-test-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = dir / "cal.yaml";
  Calibration cal = parse_calibration(kGood, "good.yaml");
  save_calibration(path, cal);
  EXPECT_EQ(format_calibration(load_calibration(path)), format_calibration(cal));
  cal.elements[0].radius_px = -1;
  EXPECT_THROW(save_calibration(path, cal), CalibrationError);
  // The good file is still there, whole.
  EXPECT_EQ(load_calibration(path).elements[0].radius_px, 14.0);
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& f : std::filesystem::directory_iterator(dir))
    ++files;
  EXPECT_EQ(files, 1U);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace tactile::config
