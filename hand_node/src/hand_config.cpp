#include "hand_config.hpp"

#include <fmt/format.h>

#include "tactile/config/calibration_file.hpp"
#include "tactile/config/controller_file.hpp"
#include "tactile/config/realtime_section.hpp"
#include "tactile/config/yaml.hpp"

namespace tactile::hand {

HandConfig load_hand_config(const std::filesystem::path& path, std::vector<std::string>* warnings) {
  const config::Node root = config::load_yaml_file(path);
  if (!root.is_map()) root.fail("a hand_node configuration must be a YAML mapping");
  root.refuse_unknown_keys({"format", "fingertips", "subscribe", "arm", "events",
                            "heartbeat_period_s", "control_period_s", "arm_timeout_s", "arm_lost_s",
                            "pair_window_s", "start_after_frames", "controller", "security",
                            "realtime"});
  const config::Node format = root["format"];
  if (format.as_string() != kHandConfigFormat) {
    format.fail(std::string("must be '") + kHandConfigFormat + "', is " + format.text());
  }
  HandConfig cfg;
  const config::Node tips = root["fingertips"];
  if (tips.size() != control::kFingertips) {
    tips.fail(
        "must list exactly 2 fingertips (0: left, squeezing toward +x of the wrist; 1: right), "
        "has " +
        std::to_string(tips.size()));
  }
  const auto base = path.parent_path();
  for (std::size_t i = 0; i < control::kFingertips; ++i) {
    const config::Node t = tips.at(i);
    t.refuse_unknown_keys({"sensor_id", "calibration"});
    FingertipConfig& f = cfg.fingertips[i];
    f.sensor_id = t["sensor_id"].as_string();
    if (f.sensor_id.empty()) t["sensor_id"].fail("must not be empty");
    const config::Node cal = t["calibration"];
    f.calibration_path = base / cal.as_string();
    f.calibration = config::load_calibration(f.calibration_path, warnings);
    if (f.calibration.sensor_id != f.sensor_id) {
      cal.fail("holds sensor '" + f.calibration.sensor_id + "', not '" + f.sensor_id + "'");
    }
    for (const auto& e : f.calibration.elements)
      f.normals.push_back(e.normal);
  }
  if (cfg.fingertips[0].sensor_id == cfg.fingertips[1].sensor_id) {
    tips.at(1)["sensor_id"].fail("repeats the sensor id of fingertip 0");
  }
  if (auto s = root.find("subscribe")) {
    cfg.subscribe.clear();
    for (std::size_t i = 0; i < s->size(); ++i)
      cfg.subscribe.push_back(s->at(i).as_string());
    if (cfg.subscribe.empty()) s->fail("must list at least one sensor_node endpoint");
  }
  cfg.arm = root.get("arm", cfg.arm);
  cfg.events = root.get("events", cfg.events);
  const auto positive = [&](const char* key, double fallback) {
    const double v = root.get(key, fallback);
    if (!(v > 0)) root[key].fail("must be a positive number of seconds, is " + root[key].text());
    return v;
  };
  cfg.heartbeat_period_s = positive("heartbeat_period_s", cfg.heartbeat_period_s);
  cfg.control_period_s = positive("control_period_s", cfg.control_period_s);
  cfg.arm_timeout_s = positive("arm_timeout_s", cfg.arm_timeout_s);
  cfg.arm_lost_s = root.get("arm_lost_s", cfg.arm_lost_s);
  if (!(cfg.arm_lost_s == 0 || (cfg.arm_lost_s >= cfg.arm_timeout_s && cfg.arm_lost_s <= 3600))) {
    root["arm_lost_s"].fail(fmt::format(
        "must be 0 (never give up) or a number of seconds from arm_timeout_s ({}) to 3600, is {}",
        cfg.arm_timeout_s, root["arm_lost_s"].text()));
  }
  cfg.pair_window_s = root.get("pair_window_s", cfg.pair_window_s);
  if (!(cfg.pair_window_s >= 0 && cfg.pair_window_s <= 1)) {
    root["pair_window_s"].fail(
        "must be 0 (off) or a number of seconds up to 1 (keep it below half "
        "the frame period), is " +
        root["pair_window_s"].text());
  }
  if (auto n = root.find("start_after_frames")) {
    const std::int64_t v = n->as_int();
    if (v < 1 || v > 10000)
      n->fail("must be a whole number of frames from 1 to 10000, is " + n->text());
    cfg.start_after_frames = static_cast<int>(v);
  }
  if (auto c = root.find("controller")) cfg.controller = config::parse_controller_config(*c);
  if (auto sec = root.find("security")) {
    sec->refuse_unknown_keys({"secret_key", "sensor_public_key", "arm_public_key"});
    const auto load = [&](const char* key, auto loader) {
      const config::Node n = (*sec)[key];
      try {
        return loader(base / n.as_string());
      } catch (const std::runtime_error& e) {
        n.fail(e.what());
      }
    };
    const wire::CurveKeyPair own = load("secret_key", wire::load_key_pair);
    cfg.sensor_security =
        wire::ClientSecurity{own, load("sensor_public_key", wire::load_public_key)};
    cfg.arm_security = wire::ClientSecurity{own, load("arm_public_key", wire::load_public_key)};
    cfg.events_security = wire::ServerSecurity{own, {}};
  }
  if (auto rt = root.find("realtime")) cfg.realtime = config::parse_realtime_section(*rt);
  return cfg;
}

}  // namespace tactile::hand
