#pragma once

#include <string>
#include <vector>

#include "tactile/config/yaml.hpp"
#include "tactile/control/config.hpp"

namespace tactile::config {

// Reads a `controller:` section: every key is a field of tactile::control::Config with the same
// name (docs/control.md lists them with units and defaults); absent keys keep their defaults.
// `twist_angle_deg` may stand for `twist_angle_rad`. A bad value throws ConfigError naming the
// file, line, key and value, and for an unknown key (naming the closest known one).
control::Config parse_controller_config(const Node& section);

// The names parse_controller_config() knows, in the order of docs/control.md.
std::vector<std::string> controller_config_keys();

// Sets one numeric field by its name (a count is rounded; twist_angle_deg converts); false for a
// name that is not a numeric field. Does not validate: call Config::validate() after the last.
bool set_controller_field(control::Config& cfg, std::string_view key, double value);

}  // namespace tactile::config
