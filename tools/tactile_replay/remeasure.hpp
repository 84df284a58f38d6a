#pragma once

// tactile_replay --remeasure: recorded raw frames back through the measurement core, each result
// checked bit for bit against the TactileFrame recorded for the same frame (docs/recording.md).
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/extractor.hpp"
#include "tactile/v1/log.pb.h"
#include "tactile/v1/tactile.pb.h"

namespace tactile::replay {

struct RemeasureOptions {
  // Measure with this estimator instead of the recorded one (to see what a change does).
  std::optional<CentroidEstimator> estimator;
  // Unmatched frames kept waiting for their partner, per sensor.
  std::size_t max_pending = 4096;
};

// The first field found to differ.
struct Difference {
  std::string sensor_id;
  std::uint64_t sequence = 0;  // TactileFrame.sequence
  std::uint64_t camera_frame_id = 0;
  std::string what;  // e.g. "element 7 (id 7) fz_n: recorded 0.53125 (0x3fe1000000000000), ..."
};

struct SensorReport {
  std::string sensor_id;
  std::uint64_t checked = 0;        // frames measured again and compared
  std::uint64_t identical = 0;      // of which identical bit for bit
  std::uint64_t unmatched_raw = 0;  // raw frames whose TactileFrame is not in the log
  std::uint64_t unchecked = 0;      // measured TactileFrames (COMPLETE) without a raw frame
  std::uint64_t no_reference = 0;   // raw frames before any reference
  std::uint64_t references = 0;     // references loaded
  std::string problem;              // why a sensor could not be checked at all
};

class Remeasurer {
 public:
  // One calibration per sensor (by sensor_id). Throws std::invalid_argument for two
  // calibrations of one sensor.
  Remeasurer(std::vector<Calibration> calibrations, RemeasureOptions options = {});
  ~Remeasurer();

  // Takes one record of the log, in log order: TactileFrames (envelopes) and raw frames; other
  // records are ignored.
  void add(const v1::LogRecord& record);
  // Counts what is still unmatched. Call once after the last record.
  void finish();

  const std::vector<SensorReport>& reports() const { return reports_; }
  const std::optional<Difference>& first_difference() const { return first_; }
  std::uint64_t differing() const { return differing_; }
  // Every measured frame was checked and identical, and something was checked.
  bool all_identical() const;
  // Sensors with raw frames or TactileFrames in the log but no calibration given.
  const std::vector<std::string>& uncalibrated() const { return uncalibrated_; }

 private:
  struct Sensor;
  Sensor* sensor(const std::string& id);
  void on_frame(const v1::TactileFrame& frame);
  void on_raw(const v1::RawFrame& raw);
  void compare(Sensor& s, const v1::TactileFrame& recorded, const v1::TactileFrame& remeasured);

  RemeasureOptions options_;
  std::vector<std::unique_ptr<Sensor>> sensors_;
  std::vector<SensorReport> reports_;
  std::vector<std::string> uncalibrated_;
  std::optional<Difference> first_;
  std::uint64_t differing_ = 0;
  v1::Envelope envelope_;
  v1::RawFrame raw_;
};

// The first field in which two TactileFrames differ (every value compared bit for bit), or
// nullopt when they are identical, serialised bytes included.
std::optional<std::string> diff_frames(const v1::TactileFrame& recorded,
                                       const v1::TactileFrame& remeasured);

}  // namespace tactile::replay
