#pragma once

// What tactile_plot gathers from a log in one pass, and the figures it draws from it.
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/control/config.hpp"
#include "tactile/control/flag_analyzer.hpp"
#include "tactile/control/slip_detector.hpp"
#include "tactile/v1/log.pb.h"
#include "tactile/v1/tactile.pb.h"

namespace tactile::plots {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct FrameSample {
  double t_s = 0;  // from the log's first record
  std::uint64_t sequence = 0;
  double max_fz_n = 0;
  double max_slip_mm = 0;  // largest per-frame displacement among in-contact elements
  double dy_mm = 0;        // signed dy of that element (or of --element)
  // The flags decided on this frame (PlotData::flag_source): hand_node's Decision that answered
  // it, or the recomputation. A frame no Decision answered holds the fingertip's latest TOUCH and
  // OVER (SLIP is decided on fresh frames only) and has `decided` false.
  bool decided = false;
  bool touch = false, slip = false, over = false;
  // Fig. 10's x: the position along the transport (finish() sets it from world_x/y_mm), NaN
  // when unknown.
  double x_mm = kNaN;
  double world_x_mm = kNaN, world_y_mm = kNaN;
  double camera_to_publish_ms = kNaN;
  double receive_to_publish_ms = kNaN;
  double publish_to_record_ms = kNaN;
};

// One element of one frame, for the maps.
struct ElementSnapshot {
  std::uint32_t id = 0;
  bool contact = false;
  double x_mm = 0, y_mm = 0, ux_mm = 0, uy_mm = 0, fx_n = 0, fy_n = 0, fz_n = 0;
};

struct Snapshot {
  double target_s = kNaN;  // the time asked for (NaN: the frame of largest total shear)
  double t_s = kNaN;       // the frame's time
  std::uint64_t sequence = 0;
  double score = -1;  // largest total shear, or minus the distance to target_s
  std::vector<ElementSnapshot> elements;
};

struct SensorData {
  std::string id;
  std::vector<FrameSample> frames;
  std::vector<Snapshot> snapshots;
  // Element positions (mm): from the calibration, or the mean in-contact centroid in the log.
  std::map<std::uint32_t, std::pair<double, double>> positions;
  std::map<std::uint32_t, std::pair<double, double>> centroid_sum;
  std::map<std::uint32_t, int> centroid_count;
  std::uint64_t incomplete = 0;
  // Element ids seen in the frames (every element appears in every frame).
  std::vector<std::uint32_t> element_ids;
  // The transport direction (unit, world x/y) Fig. 10's x is measured along; world x when the
  // fingertip did not move between its first and last touch.
  double transport_x = 1, transport_y = 0;
  bool transport_known = false;
};

struct EventMark {
  double t_s = 0;
  std::string kind;
  std::string text;
  std::uint32_t cycle = 0;
};

struct PlotOptions {
  std::vector<double> at_s;              // snapshot times; empty: the frame of largest total shear
  std::vector<std::string> sensors;      // empty: every sensor
  std::optional<std::uint32_t> element;  // Fig. 10: this element's dy instead of the largest
  control::Config control;               // F1, F2, dr (and the detector's parameters)
  // Decide the flags here with this detector (common/control) instead of drawing hand_node's
  // Decisions from the log; no arm motion is used.
  std::optional<control::SlipDetectorKind> recompute;
  std::vector<Calibration> calibrations;
  int width = 1000;
  int height = 700;
};

// Where Fig. 10's fingertip x comes from.
enum class PositionSource { kNone, kGroundTruth, kArmState };

// Where the flags drawn come from (docs/architecture.md, rule 15).
enum class FlagSource { kNone, kHandNode, kRecomputed };

class PlotData {
 public:
  explicit PlotData(PlotOptions options);
  void add(const v1::LogRecord& record);
  void finish();

  const std::vector<SensorData>& sensors() const { return sensors_; }
  const std::vector<EventMark>& events() const { return events_; }
  PositionSource position_source() const { return source_; }
  std::string position_source_text() const;
  FlagSource flag_source() const;
  // The flags' source for the figures' titles: "flags: hand_node (learned)", "flags: recomputed
  // (paper)", or that the log holds no hand_node decisions.
  std::string flag_source_text() const;
  const PlotOptions& options() const { return options_; }
  // The log's first and last frame time (s from its first record), for --at.
  std::optional<std::pair<double, double>> frame_time_range() const;

 private:
  SensorData* sensor(const std::string& id);
  void on_frame(const v1::TactileFrame& f, double t, std::int64_t receive_ns);
  void on_decision(const v1::Decision& d);
  void snapshot(SensorData& s, const v1::TactileFrame& f, double t);

  PlotOptions options_;
  control::FlagAnalyzer flags_;
  std::vector<SensorData> sensors_;
  // --recompute: one detector per sensor (in sensors_' order), each deciding in its slot 0.
  std::vector<control::SlipDetector> detectors_;
  bool decisions_ = false;  // the log holds hand_node's Decisions
  std::string detector_;    // the latest Decision's slip_detector
  std::vector<EventMark> events_;
  std::optional<std::int64_t> first_ns_;
  PositionSource source_ = PositionSource::kNone;
  double truth_x_mm_ = kNaN, truth_y_mm_ = kNaN;
  std::map<std::string, std::pair<double, double>> arm_xy_mm_;  // per fingertip sensor id
  bool twist_phase_ = false;
  v1::Envelope envelope_;
  std::vector<ElementReading> readings_;
};

// Each figure writes one or more PNG files into `dir` and returns their paths.
std::vector<std::filesystem::path> draw_shear_fields(const PlotData& d,
                                                     const std::filesystem::path& dir);
std::vector<std::filesystem::path> draw_fig10(const PlotData& d, const std::filesystem::path& dir);
std::vector<std::filesystem::path> draw_force_maps(const PlotData& d,
                                                   const std::filesystem::path& dir);
std::vector<std::filesystem::path> draw_timeline(const PlotData& d,
                                                 const std::filesystem::path& dir);
std::vector<std::filesystem::path> draw_latency(const PlotData& d,
                                                const std::filesystem::path& dir);

}  // namespace tactile::plots
