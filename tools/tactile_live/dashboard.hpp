#pragma once

// tactile_live's model and its rendering. LiveModel takes the messages (frames, stats, events)
// and keeps the latest state; render() draws that state as text: a pure function of the state
// and the screen size, so it is tested on fixed states (golden text).
#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/control/config.hpp"
#include "tactile/control/flag_analyzer.hpp"
#include "tactile/control/slip_detector.hpp"
#include "tactile/reading.hpp"
#include "tactile/v1/tactile.pb.h"
#include "tactile/wire/envelope.hpp"

namespace tactile::live {

struct ElementCell {
  std::uint32_t id = 0;
  bool contact = false;
  bool slip = false;  // marked slipping by the decision shown (LiveState::flags_from)
  double fz_n = 0;
  double fx_n = 0;  // shear force F_x, F_y
  double fy_n = 0;
};

struct FingertipView {
  std::string id;
  std::vector<ElementCell> elements;
  std::uint64_t sequence = 0;
  std::string_view status = "-";  // FrameStatus of the latest frame, without its prefix
  double fps = 0;                 // whole frames per second over the last second
  std::uint64_t lost = 0;         // gaps in the TactileFrame sequence
  // The flags of the decision shown (LiveState::flags_from); `decided` false: none yet.
  bool decided = false;
  bool touch = false, slip = false, over = false;
  // Measured on the latest whole frame: the largest F_z and displacement in contact.
  double max_fz_n = 0;
  double max_slip_mm = 0;
  double age_s = 0;  // since the latest frame
  // From the latest SensorStats.
  bool has_stats = false;
  std::uint64_t camera_frames = 0;
  std::uint64_t incomplete = 0;
  double measure_us_p50 = 0;
};

struct EventLine {
  std::int64_t time_ns = 0;  // the event's time (CLOCK_REALTIME of hand_node)
  std::string kind;          // without the EVENT_KIND_ prefix
  std::string detail;
};

// Where the flags and slipping elements shown come from (docs/architecture.md, rule 15):
// hand_node's Decisions (topic `decision`), the model's own detector when asked (--recompute), or
// nowhere yet.
enum class FlagSource : std::uint8_t { kNone, kHandNode, kRecomputed };
// "hand_node", "recomputed" or "none": the JSON's and line mode's name.
const char* to_string(FlagSource source);

struct TopicRate {
  std::string topic;
  double per_s = 0;
};

struct LiveState {
  std::int64_t now_ns = 0;  // CLOCK_REALTIME: the clock shown
  std::vector<std::string> endpoints;
  std::vector<FingertipView> fingertips;
  std::string phase = "-";
  std::uint32_t cycle = 0;
  FlagSource flags_from = FlagSource::kNone;
  // The detector that decided: hand_node's Decision.slip_detector ("" from an older hand_node),
  // or the one recomputing.
  std::string detector;
  std::deque<EventLine> events;    // newest last
  std::uint64_t events_total = 0;  // every event so far: the newest is number events_total - 1
  std::vector<TopicRate> rates;
  std::uint64_t messages = 0;
  std::uint64_t undecodable = 0;
};

// Where each element sits on the dome, in any unit with y down (image rows): the calibration's
// disk centres, or for a sensor without one rings of 1, 8, 16, 16, ... elements in id order (the
// paper's 41-element layout).
std::vector<std::array<double, 2>> dome_layout(std::size_t count, const Calibration* cal);

// Where the fingertips go in a window of `width` x `height` characters below `header_lines`
// lines of header: a pure function of their ids and the window, so the screen follows a resize
// at the next redraw.
struct ScreenLayout {
  // Indices into the fingertips in drawing order, left to right (or top to bottom): "left"
  // first and "right" last whatever order their frames arrived in, any other id between, by id.
  std::vector<std::size_t> order;
  bool side_by_side = true;
  int block_width = 0;  // columns of one fingertip's block
  int grid_rows = 0;    // rows of one dome; 0 when the window is too small (summaries only)
};
ScreenLayout screen_layout(std::span<const FingertipView> fingertips, int width, int height,
                           int header_lines);

struct RenderOptions {
  int width = 80;
  int height = 24;
  bool color = false;
  double f2_n = 2.5;  // force digits are F_z / F2 in ninths
};

// The whole screen as lines separated by '\n' (no cursor movement); at most `height` lines of at
// most `width` visible characters.
std::string render(const LiveState& state, std::span<const Calibration> calibrations,
                   const RenderOptions& options);

// Who decided the flags shown, for the screen, appended to `out`: "flags: hand_node (learned)",
// "flags: recomputed (paper)", or that no hand_node decision has arrived. Allocates nothing once
// `out` has room.
void append_flags_label(const LiveState& state, std::string& out);

// Line mode: one line per fingertip (for a pipe or a log file).
std::string summary_lines(const LiveState& state);
std::string event_line(const EventLine& e);

struct ModelOptions {
  control::Config control;  // F1, F2, dr (and the detector's parameters) for --recompute
  std::size_t max_events = 8;
  // Decide the flags here with this detector (common/control's SlipDetector and FlagAnalyzer)
  // instead of showing hand_node's Decisions; no arm motion is known here.
  std::optional<control::SlipDetectorKind> recompute;
};

class LiveModel {
 public:
  explicit LiveModel(ModelOptions options, std::vector<std::string> endpoints = {});

  // One message; `now_mono_ns` is the monotonic time it arrived. Returns the event's line index
  // when the message was an Event (for line mode), -1 otherwise.
  int add(std::string_view topic, std::span<const std::uint8_t> payload, std::int64_t now_mono_ns);
  // Brings rates and ages to `now_mono_ns` and the clock to `now_real_ns`.
  void tick(std::int64_t now_mono_ns, std::int64_t now_real_ns);
  const LiveState& state() const { return state_; }

 private:
  FingertipView& fingertip(const std::string& id, std::size_t& index);
  void count(std::string_view topic, std::int64_t now);
  void on_frame(const v1::TactileFrame& frame, std::int64_t now);
  void on_decision(const v1::Decision& decision);
  // Marks fingertip k's elements slipping that its latest decision names.
  void mark_slipping(std::size_t k);

  ModelOptions options_;
  control::FlagAnalyzer flags_;
  // --recompute: one detector per fingertip shown, each deciding its fingertip in slot 0.
  std::vector<control::SlipDetector> detectors_;
  // Per fingertip: the ids its latest decision marked slipping.
  struct Slipping {
    std::array<std::uint32_t, control::kMaxSlipElements> ids{};
    std::size_t count = 0;
  };
  std::vector<Slipping> slipping_;
  LiveState state_;
  wire::EnvelopeDecoder decoder_;
  std::vector<ElementReading> readings_;
  // Messages counted over windows of about a second; the rate is that of the last whole window.
  struct Counter {
    std::string topic;
    std::uint64_t count = 0;
    std::int64_t since_ns = 0;
    double rate = 0;
  };
  std::vector<Counter> counters_;
  std::vector<Counter> frame_counters_;  // per fingertip, whole frames
  std::vector<std::int64_t> last_frame_ns_;
  std::vector<std::optional<std::uint64_t>> last_sequence_;
  bool twist_phase_ = false;
};

}  // namespace tactile::live
