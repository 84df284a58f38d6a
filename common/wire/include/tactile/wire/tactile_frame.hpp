#pragma once

// TactileFrame <-> measurement core readings. Pure functions: no sockets, no clocks.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/reading.hpp"
#include "tactile/v1/tactile.pb.h"
#include "tactile/wire/envelope.hpp"

namespace tactile::wire {

// Everything of a TactileFrame but the element readings.
struct FrameHeader {
  std::uint64_t sequence = 0;
  std::uint64_t camera_frame_id = 0;
  std::int64_t camera_timestamp_ns = 0;
  std::int64_t receive_timestamp_ns = 0;
  std::int64_t publish_timestamp_ns = 0;
  v1::FrameStatus status = v1::FRAME_STATUS_UNSPECIFIED;
  std::int64_t nominal_period_ns = 0;
  std::uint32_t frames_skipped = 0;
  double measure_time_us = 0;
};

// Fills `out` (reused: after the first frame its element messages are recycled, so a steady
// stream allocates nothing here). Readings are written only for COMPLETE frames; centroids are
// converted from pixels to mm with the calibration's scale.
void fill_tactile_frame(const std::string& sensor_id, const FrameHeader& header,
                        std::span<const ElementReading> readings, double mm_per_px,
                        v1::TactileFrame& out);

// A received TactileFrame checked against the sensor's calibration, in core types.
struct ReceivedFrame {
  FrameHeader header;
  std::vector<ElementReading> elements;  // sized to the calibration once, reused
};

// Checks and converts: a COMPLETE frame must carry exactly the calibration's elements in order,
// every number finite; other statuses carry none. Returns kInvalid otherwise (out unchanged in
// meaning: the caller must not use it). Centroids come back in pixels. Never throws, and does
// not allocate once `out.elements` has the calibration's size.
DecodeStatus read_tactile_frame(const v1::TactileFrame& in, const Calibration& cal,
                                ReceivedFrame& out) noexcept;

// The element readings of a received frame with no calibration to check them against (the
// viewers): every element as it came, in its order, checked and converted as read_tactile_frame
// does, except that the centroids stay in mm (x_px, y_px hold mm: no scale is known). A frame
// that is not COMPLETE gives none. kInvalid when a number is not finite (`out` then unusable).
// Does not allocate once `out` has the frame's size.
DecodeStatus read_elements(const v1::TactileFrame& in, std::vector<ElementReading>& out) noexcept;

}  // namespace tactile::wire
