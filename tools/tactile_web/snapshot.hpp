#pragma once

// What tactile_web sends the page: the live model's state (tactile_live's LiveModel, the one
// place that turns messages into flags, phase and events) as one JSON object per update, written
// into a buffer whose capacity is kept from update to update.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "dashboard.hpp"
#include "tactile/calibration.hpp"
#include "tactile/control/config.hpp"

namespace tactile::web {

struct UpdateCounters {
  std::uint64_t update = 0;     // this update's number, from 1
  std::uint64_t coalesced = 0;  // updates a viewer did not get because a newer one replaced them
  std::uint64_t streams = 0;    // viewers connected now
};

class SnapshotWriter {
 public:
  // `control` gives the thresholds the page draws against (F1, F2, dr).
  SnapshotWriter(std::vector<Calibration> calibrations, const control::Config& control)
      : calibrations_(std::move(calibrations)), control_(control) {}

  // The whole state as one line of JSON in `out` (its old content replaced). The element
  // positions are the calibration's disk centres, else the 41-element rings (live::dome_layout),
  // computed once per fingertip.
  void write(const live::LiveState& state, const UpdateCounters& counters, std::string& out);
  // The update's point of the page's rolling charts (time_ns, f2_n, dr_mm and each fingertip's
  // id, max_fz_n and max_slip_mm, named as in the update) as one JSON object in `out`: what
  // tactile_web keeps of past updates for a page that joins late (UpdateSlot).
  void write_point(const live::LiveState& state, std::string& out) const;

 private:
  const std::vector<std::array<double, 2>>& layout(const live::FingertipView& f);

  std::vector<Calibration> calibrations_;
  control::Config control_;
  struct Layout {
    std::string id;
    std::size_t count = 0;
    std::vector<std::array<double, 2>> positions;
  };
  std::vector<Layout> layouts_;
  std::string label_;  // the flags' label, escaped into the update
};

}  // namespace tactile::web
