#include "sensor_config.hpp"

#include "tactile/config/calibration_file.hpp"
#include "tactile/config/realtime_section.hpp"
#include "tactile/config/yaml.hpp"

namespace tactile::sensor {

SensorConfig default_sensor_config() {
  SensorConfig cfg;
  // Slip is computed only across consecutive whole frames (a lost frame restarts it).
  cfg.measurement.max_gap_frames = 1;
  // A camera's region of interest (roi: auto) delivers the part of the image that holds every
  // element's disk: measured exactly as the whole frame.
  cfg.measurement.accept_regions = true;
  return cfg;
}

void finish_camera_config(CameraConfig& c) {
  c.camera.width = c.calibration.width;
  c.camera.height = c.calibration.height;
  c.camera.pixel_format = c.calibration.bit_depth == 8 ? PixelFormat::kMono8 : PixelFormat::kMono16;
  c.camera.region = c.roi_auto ? region_of_interest(c.calibration) : Region{};
  c.camera.validate();
}

namespace {

double positive(const config::Node& n, const char* key, double fallback) {
  const double v = n.get(key, fallback);
  if (!(v > 0)) n[key].fail("must be a positive number, is " + n[key].text());
  return v;
}

}  // namespace

SensorConfig load_sensor_config(const std::filesystem::path& path,
                                std::vector<std::string>* warnings,
                                const std::filesystem::path& state_dir) {
  const config::Node root = config::load_yaml_file(path);
  if (!root.is_map()) root.fail("a sensor_node configuration must be a YAML mapping");
  root.refuse_unknown_keys({"format", "publish", "stats_period_s", "raw_frames", "measurement",
                            "cameras", "security", "realtime"});
  const config::Node format = root["format"];
  if (format.as_string() != kSensorConfigFormat) {
    format.fail(std::string("must be '") + kSensorConfigFormat + "', is " + format.text());
  }
  SensorConfig cfg = default_sensor_config();
  cfg.publish = root.get("publish", cfg.publish);
  cfg.stats_period_s = positive(root, "stats_period_s", cfg.stats_period_s);
  cfg.raw_frames = root.get("raw_frames", cfg.raw_frames);
  if (auto m = root.find("measurement")) {
    m->refuse_unknown_keys(
        {"estimator", "reference_frames", "reference_spot_check", "max_gap_frames"});
    if (auto e = m->find("estimator")) {
      const auto est = parse_estimator(e->as_string());
      if (!est) e->fail(std::string("must be ") + kEstimatorNames + ", is " + e->text());
      cfg.measurement.estimator = *est;
    }
    cfg.measurement.reference_frames = m->get("reference_frames", cfg.measurement.reference_frames);
    if (cfg.measurement.reference_frames < 1 || cfg.measurement.reference_frames > 65536) {
      (*m)["reference_frames"].fail("must be 1..65536, is " + (*m)["reference_frames"].text());
    }
    cfg.measurement.reference_spot_check =
        m->get("reference_spot_check", cfg.measurement.reference_spot_check);
    const int gap = m->get("max_gap_frames", static_cast<int>(cfg.measurement.max_gap_frames));
    if (gap < 1 || gap > 1000)
      (*m)["max_gap_frames"].fail("must be 1..1000, is " + (*m)["max_gap_frames"].text());
    cfg.measurement.max_gap_frames = static_cast<std::uint32_t>(gap);
  }
  if (auto sec = root.find("security")) {
    sec->refuse_unknown_keys({"secret_key"});
    const config::Node key = (*sec)["secret_key"];
    try {
      cfg.security =
          wire::ServerSecurity{wire::load_key_pair(path.parent_path() / key.as_string()), {}};
    } catch (const std::runtime_error& e) {
      key.fail(e.what());
    }
  }
  if (auto rt = root.find("realtime")) cfg.realtime = config::parse_realtime_section(*rt);
  const config::Node cams = root["cameras"];
  if (cams.size() == 0) cams.fail("must list at least one camera");
  const auto base = path.parent_path();
  for (std::size_t i = 0; i < cams.size(); ++i) {
    const config::Node c = cams.at(i);
    c.refuse_unknown_keys({"sensor_id", "camera", "calibration", "reference", "reference_cache",
                           "fps", "packet_size", "packet_delay_ns", "socket_buffer_bytes",
                           "buffers", "interface", "packet_resend", "roi", "frame_timeout_s",
                           "retry_initial_s", "retry_max_s"});
    CameraConfig cc;
    cc.sensor_id = c["sensor_id"].as_string();
    for (const auto& other : cfg.cameras) {
      if (other.sensor_id == cc.sensor_id)
        c["sensor_id"].fail("repeats sensor id '" + cc.sensor_id + "'");
    }
    cc.camera.camera = c["camera"].as_string();
    cc.calibration_path = base / c["calibration"].as_string();
    cc.calibration = config::load_calibration(cc.calibration_path, warnings);
    if (cc.calibration.sensor_id != cc.sensor_id) {
      c["calibration"].fail("holds sensor '" + cc.calibration.sensor_id + "', not '" +
                            cc.sensor_id + "'");
    }
    if (auto r = c.find("reference")) cc.reference = base / r->as_string();
    if (auto r = c.find("reference_cache"))
      cc.reference_cache = (state_dir.empty() ? base : state_dir) / r->as_string();
    cc.camera.frame_rate_hz = positive(c, "fps", cc.camera.frame_rate_hz);
    cc.camera.packet_size_bytes = c.get("packet_size", cc.camera.packet_size_bytes);
    cc.camera.packet_delay_ns = c.get("packet_delay_ns", cc.camera.packet_delay_ns);
    const std::int64_t sock =
        c.get("socket_buffer_bytes", static_cast<std::int64_t>(cc.camera.socket_buffer_bytes));
    if (sock <= 0)
      c["socket_buffer_bytes"].fail("must be positive, is " + c["socket_buffer_bytes"].text());
    cc.camera.socket_buffer_bytes = static_cast<std::size_t>(sock);
    cc.camera.buffer_count = c.get("buffers", cc.camera.buffer_count);
    cc.camera.interface_address = c.get("interface", cc.camera.interface_address);
    cc.camera.packet_resend = c.get("packet_resend", cc.camera.packet_resend);
    if (auto roi = c.find("roi")) {
      const std::string v = roi->as_string();
      if (v != "auto" && v != "full") roi->fail("must be auto or full, is " + roi->text());
      cc.roi_auto = v == "auto";
    }
    cc.frame_timeout_s = positive(c, "frame_timeout_s", cc.frame_timeout_s);
    cc.retry_initial_s = positive(c, "retry_initial_s", cc.retry_initial_s);
    cc.retry_max_s = positive(c, "retry_max_s", cc.retry_max_s);
    try {
      finish_camera_config(cc);
    } catch (const std::invalid_argument& e) {
      c.fail(e.what());
    }
    cfg.cameras.push_back(std::move(cc));
  }
  return cfg;
}

}  // namespace tactile::sensor
