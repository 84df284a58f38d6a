#include "remeasure.hpp"

#include <fmt/format.h>

#include <bit>
#include <stdexcept>

#include "tactile/wire/envelope.hpp"
#include "tactile/wire/raw_frame.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::replay {

struct Remeasurer::Sensor {
  std::size_t report = 0;
  Calibration cal;
  std::unique_ptr<Extractor> extractor;
  std::string settings;   // serialised MeasurementSettings the extractor was made with
  std::string reference;  // pixels of the reference loaded last
  std::map<std::uint64_t, v1::TactileFrame> recorded;    // waiting for their raw frame
  std::map<std::uint64_t, v1::TactileFrame> remeasured;  // waiting for their TactileFrame
  std::vector<std::uint8_t> scratch;
};

namespace {

std::string describe(double recorded, double remeasured) {
  return fmt::format("recorded {:.17g} ({:#018x}), remeasured {:.17g} ({:#018x})", recorded,
                     std::bit_cast<std::uint64_t>(recorded), remeasured,
                     std::bit_cast<std::uint64_t>(remeasured));
}

}  // namespace

std::optional<std::string> diff_frames(const v1::TactileFrame& a, const v1::TactileFrame& b) {
  if (a.status() != b.status()) {
    return fmt::format("status: recorded {}, remeasured {}", v1::FrameStatus_Name(a.status()),
                       v1::FrameStatus_Name(b.status()));
  }
  if (a.elements_size() != b.elements_size()) {
    return fmt::format("element count: recorded {}, remeasured {}", a.elements_size(),
                       b.elements_size());
  }
  for (int i = 0; i < a.elements_size(); ++i) {
    const v1::ElementReading& x = a.elements(i);
    const v1::ElementReading& y = b.elements(i);
    const std::string where = fmt::format("element {} (id {})", i, x.id());
    if (x.id() != y.id()) return fmt::format("{}: id remeasured {}", where, y.id());
    if (x.contact() != y.contact()) {
      return fmt::format("{} contact: recorded {}, remeasured {}", where, x.contact(), y.contact());
    }
    if (x.has_displacement() != y.has_displacement()) {
      return fmt::format("{} has_displacement: recorded {}, remeasured {}", where,
                         x.has_displacement(), y.has_displacement());
    }
    const std::pair<const char*, std::pair<double, double>> values[] = {
        {"g", {x.g(), y.g()}},
        {"x_mm", {x.x_mm(), y.x_mm()}},
        {"y_mm", {x.y_mm(), y.y_mm()}},
        {"dx_mm", {x.dx_mm(), y.dx_mm()}},
        {"dy_mm", {x.dy_mm(), y.dy_mm()}},
        {"ux_mm", {x.ux_mm(), y.ux_mm()}},
        {"uy_mm", {x.uy_mm(), y.uy_mm()}},
        {"fx_n", {x.fx_n(), y.fx_n()}},
        {"fy_n", {x.fy_n(), y.fy_n()}},
        {"fz_n", {x.fz_n(), y.fz_n()}}};
    for (const auto& [name, v] : values) {
      if (std::bit_cast<std::uint64_t>(v.first) != std::bit_cast<std::uint64_t>(v.second)) {
        return fmt::format("{} {}: {}", where, name, describe(v.first, v.second));
      }
    }
  }
  if (a.SerializeAsString() != b.SerializeAsString()) {
    return std::string("serialised bytes differ (a field outside the readings)");
  }
  return std::nullopt;
}

Remeasurer::Remeasurer(std::vector<Calibration> calibrations, RemeasureOptions options)
    : options_(options) {
  for (auto& c : calibrations) {
    for (const auto& s : sensors_) {
      if (s->cal.sensor_id == c.sensor_id) {
        throw std::invalid_argument("two calibrations of sensor '" + c.sensor_id + "'");
      }
    }
    auto s = std::make_unique<Sensor>();
    s->cal = std::move(c);
    s->report = reports_.size();
    SensorReport report;
    report.sensor_id = s->cal.sensor_id;
    reports_.push_back(std::move(report));
    sensors_.push_back(std::move(s));
  }
}

Remeasurer::~Remeasurer() = default;

Remeasurer::Sensor* Remeasurer::sensor(const std::string& id) {
  for (auto& s : sensors_) {
    if (s->cal.sensor_id == id) return s.get();
  }
  for (const auto& u : uncalibrated_) {
    if (u == id) return nullptr;
  }
  uncalibrated_.push_back(id);
  return nullptr;
}

void Remeasurer::add(const v1::LogRecord& record) {
  if (record.kind() == v1::PAYLOAD_KIND_RAW_FRAME) {
    if (raw_.ParseFromString(record.payload())) on_raw(raw_);
    return;
  }
  if (record.kind() != v1::PAYLOAD_KIND_ENVELOPE) return;
  if (wire::decode(wire::bytes_of(record.payload()), envelope_) != wire::DecodeStatus::kOk) return;
  if (envelope_.has_tactile_frame()) on_frame(envelope_.tactile_frame());
}

void Remeasurer::compare(Sensor& s, const v1::TactileFrame& recorded,
                         const v1::TactileFrame& remeasured_readings) {
  // The header is what the run measured around the core (times, ids): take it from the record;
  // status and readings are the core's.
  v1::TactileFrame e = recorded;
  e.set_status(remeasured_readings.status());
  *e.mutable_elements() = remeasured_readings.elements();
  SensorReport& r = reports_[s.report];
  ++r.checked;
  const auto d = diff_frames(recorded, e);
  if (!d) {
    ++r.identical;
    return;
  }
  ++differing_;
  if (!first_) {
    first_ = Difference{s.cal.sensor_id, recorded.sequence(), recorded.camera_frame_id(), *d};
  }
}

void Remeasurer::on_frame(const v1::TactileFrame& frame) {
  Sensor* s = sensor(frame.sensor_id());
  if (s == nullptr) return;
  if (frame.status() != v1::FRAME_STATUS_COMPLETE &&
      frame.status() != v1::FRAME_STATUS_WRONG_FORMAT) {
    return;  // not measured by the core
  }
  SensorReport& r = reports_[s->report];
  const std::uint64_t seq = frame.sequence();
  // Remeasured frames older than this one will never see theirs (frames arrive in order).
  while (!s->remeasured.empty() && s->remeasured.begin()->first < seq) {
    ++r.unmatched_raw;
    s->remeasured.erase(s->remeasured.begin());
  }
  const auto it = s->remeasured.find(seq);
  if (it != s->remeasured.end()) {
    compare(*s, frame, it->second);
    s->remeasured.erase(it);
    return;
  }
  s->recorded[seq] = frame;
  if (s->recorded.size() > options_.max_pending) {
    if (s->recorded.begin()->second.status() == v1::FRAME_STATUS_COMPLETE) ++r.unchecked;
    s->recorded.erase(s->recorded.begin());
  }
}

void Remeasurer::on_raw(const v1::RawFrame& raw) {
  Sensor* s = sensor(raw.sensor_id());
  if (s == nullptr) return;
  SensorReport& r = reports_[s->report];
  ImageView view;
  std::string why;
  if (raw.kind() == v1::RAW_FRAME_KIND_REFERENCE) {
    std::string settings = raw.settings().SerializeAsString();
    if (!s->extractor || settings != s->settings) {
      ExtractorOptions o;
      try {
        o = wire::to_options(raw.settings());
      } catch (const std::exception& e) {
        r.problem = e.what();
        return;
      }
      if (options_.estimator) o.estimator = *options_.estimator;
      try {
        s->extractor = std::make_unique<Extractor>(s->cal, o);
      } catch (const std::exception& e) {
        r.problem = std::string("calibration: ") + e.what();
        return;
      }
      s->settings = std::move(settings);
      s->reference.clear();
    }
    if (raw.pixels() == s->reference) return;  // the same reference again
    if (!wire::raw_view(raw, s->scratch, view, why)) {
      r.problem = "a recorded reference is not an image: " + why;
      return;
    }
    s->extractor->begin_reference();
    ReferenceResult rr = s->extractor->add_reference_frame(view);
    if (rr.status == ReferenceStatus::kCollecting) rr = s->extractor->finish_reference();
    if (rr.status != ReferenceStatus::kComplete) {
      r.problem = std::string("the recorded reference is refused by the core: ") +
                  to_string(rr.status) + " (element " + std::to_string(rr.element_id) + ")";
      s->extractor.reset();
      return;
    }
    s->reference = raw.pixels();
    ++r.references;
    return;
  }
  if (raw.kind() != v1::RAW_FRAME_KIND_MEASURED) return;
  if (!s->extractor || !s->extractor->has_reference()) {
    ++r.no_reference;
    return;
  }
  if (!wire::raw_view(raw, s->scratch, view, why)) {
    r.problem = "a recorded raw frame is not an image: " + why;
    return;
  }
  if (raw.forget_previous()) s->extractor->forget_previous();
  const MeasureStatus ms = s->extractor->measure(view, {raw.sequence(), raw.camera_timestamp_ns()});
  wire::FrameHeader h;
  h.status = ms == MeasureStatus::kOk ? v1::FRAME_STATUS_COMPLETE : v1::FRAME_STATUS_WRONG_FORMAT;
  v1::TactileFrame e;
  wire::fill_tactile_frame(s->cal.sensor_id, h, s->extractor->readings(), s->cal.mm_per_px, e);
  const std::uint64_t seq = raw.tactile_sequence();
  // Recorded frames older than this one will never see their raw frame.
  while (!s->recorded.empty() && s->recorded.begin()->first < seq) {
    if (s->recorded.begin()->second.status() == v1::FRAME_STATUS_COMPLETE) ++r.unchecked;
    s->recorded.erase(s->recorded.begin());
  }
  const auto it = s->recorded.find(seq);
  if (it != s->recorded.end()) {
    compare(*s, it->second, e);
    s->recorded.erase(it);
    return;
  }
  s->remeasured[seq] = std::move(e);
  if (s->remeasured.size() > options_.max_pending) {
    ++r.unmatched_raw;
    s->remeasured.erase(s->remeasured.begin());
  }
}

void Remeasurer::finish() {
  for (auto& s : sensors_) {
    SensorReport& r = reports_[s->report];
    for (const auto& [seq, f] : s->recorded) {
      if (f.status() == v1::FRAME_STATUS_COMPLETE) ++r.unchecked;
    }
    r.unmatched_raw += s->remeasured.size();
    s->recorded.clear();
    s->remeasured.clear();
  }
}

bool Remeasurer::all_identical() const {
  std::uint64_t checked = 0;
  for (const auto& r : reports_) {
    if (!r.problem.empty()) return false;
    checked += r.checked;
  }
  return checked > 0 && differing_ == 0;
}

}  // namespace tactile::replay
