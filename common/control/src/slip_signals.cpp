#include "tactile/control/slip_signals.hpp"

namespace tactile::control {

const std::array<const char*, kSlipFeatures> kSlipFeatureNames{"moved_dr",
                                                               "departed_dr",
                                                               "surface_dr",
                                                               "load",
                                                               "load_prev",
                                                               "fz_n",
                                                               "dfz_n",
                                                               "moved_prev_dr",
                                                               "departed_prev_dr",
                                                               "rigid_dr",
                                                               "rotation_dr",
                                                               "arm_speed_mmps",
                                                               "arm_yaw_dps",
                                                               "share_moved",
                                                               "share_departed",
                                                               "total_fz_n",
                                                               "total_dfz_rel",
                                                               "field_reasons",
                                                               "field_was",
                                                               "measured",
                                                               "dr_um",
                                                               "mu",
                                                               "ft_n",
                                                               "align",
                                                               "moved_prev2_dr",
                                                               "dfz_prev_n",
                                                               "arm_dr",
                                                               "fps",
                                                               "share_slipping",
                                                               "share_slipping_prev"};

const char* to_string(SlipSignal s) {
  const auto k = column(s);
  return k < kSlipFeatures ? kSlipFeatureNames[k] : "?";
}

}  // namespace tactile::control
