#pragma once

// Between the control core and the simulated world, for the lockstep runner and the real-time
// rig alike. Pure conversions.
#include "tactile/control/config.hpp"
#include "tactile/control/types.hpp"
#include "tactile/rig/scenario.hpp"
#include "tactile/rig/world.hpp"

namespace tactile::rig {

// The control core's configuration of a scenario: defaults, the scenario's cap and bottle, and
// its `controller` overrides. Throws std::invalid_argument for an invalid result.
control::Config scenario_controller_config(const Scenario& scenario);

// The arm command the world carries out for a control-core command.
ArmCommand to_world_command(const control::Command& c);

}  // namespace tactile::rig
