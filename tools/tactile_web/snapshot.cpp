#include "snapshot.hpp"

#include <fmt/format.h>

#include <cmath>
#include <iterator>

namespace tactile::web {
namespace {

// JSON has no NaN or infinity; the model lets none out (docs/architecture.md, rule 4), but a
// page must never get a line it cannot parse.
double finite(double v) {
  return std::isfinite(v) ? v : 0.0;
}

void append_string(std::string& out, std::string_view s) {
  out += '"';
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20) {
      fmt::format_to(std::back_inserter(out), "\\u{:04x}", u);
    } else {
      out += c;
    }
  }
  out += '"';
}

}  // namespace

const std::vector<std::array<double, 2>>& SnapshotWriter::layout(const live::FingertipView& f) {
  for (auto& l : layouts_) {
    if (l.id == f.id && l.count == f.elements.size()) return l.positions;
  }
  const Calibration* cal = nullptr;
  for (const auto& c : calibrations_) {
    if (c.sensor_id == f.id) cal = &c;
  }
  layouts_.push_back({f.id, f.elements.size(), live::dome_layout(f.elements.size(), cal)});
  return layouts_.back().positions;
}

void SnapshotWriter::write(const live::LiveState& s, const UpdateCounters& c, std::string& out) {
  // Room for two fingertips of 41 elements and the latest events from the first update on, so
  // that the buffers passed around do not grow update by update (docs/architecture.md, rule 4).
  constexpr std::size_t kRoom = 64 << 10;
  if (out.capacity() < kRoom) out.reserve(kRoom);
  out.clear();
  auto o = std::back_inserter(out);
  fmt::format_to(o, R"({{"update":{},"coalesced":{},"streams":{},"time_ns":{},"messages":{},)",
                 c.update, c.coalesced, c.streams, s.now_ns, s.messages);
  fmt::format_to(o, R"("undecodable":{},"f1_n":{},"f2_n":{},"dr_mm":{},"phase":)", s.undecodable,
                 control_.f1_n, control_.f2_n, control_.dr_mm);
  append_string(out, s.phase);
  // Who decided the flags and slipping elements (docs/architecture.md, rule 15), and the line
  // the page shows for it.
  fmt::format_to(o, R"(,"flags_from":"{}","detector":)", live::to_string(s.flags_from));
  append_string(out, s.detector);
  label_.clear();
  live::append_flags_label(s, label_);
  out += R"(,"flags_label":)";
  append_string(out, label_);
  fmt::format_to(o, R"(,"cycle":{},"fingertips":[)", s.cycle);
  for (std::size_t i = 0; i < s.fingertips.size(); ++i) {
    const live::FingertipView& f = s.fingertips[i];
    if (i > 0) out += ',';
    out += R"({"id":)";
    append_string(out, f.id);
    fmt::format_to(o, R"(,"sequence":{},"status":)", f.sequence);
    append_string(out, f.status);
    fmt::format_to(o,
                   R"(,"fps":{:.1f},"lost":{},"age_s":{:.2f},"decided":{},"touch":{},"slip":{},)"
                   R"("over":{},)",
                   finite(f.fps), f.lost, finite(f.age_s), f.decided, f.touch, f.slip, f.over);
    fmt::format_to(o, R"("max_fz_n":{},"max_slip_mm":{},"elements":[)", finite(f.max_fz_n),
                   finite(f.max_slip_mm));
    const auto& pos = layout(f);
    for (std::size_t k = 0; k < f.elements.size(); ++k) {
      const live::ElementCell& e = f.elements[k];
      if (k > 0) out += ',';
      // Shortest round-trip text: the page shows what the frame held, digit for digit.
      fmt::format_to(o, R"({{"id":{},"x":{},"y":{},"contact":{},"slip":{},"fz":{},"fx":{},)", e.id,
                     finite(pos[k][0]), finite(pos[k][1]), e.contact, e.slip, finite(e.fz_n),
                     finite(e.fx_n));
      fmt::format_to(o, R"("fy":{}}})", finite(e.fy_n));
    }
    out += "]}";
  }
  fmt::format_to(o, R"(],"events_total":{},"events":[)", s.events_total);
  for (std::size_t k = 0; k < s.events.size(); ++k) {
    const live::EventLine& e = s.events[k];
    if (k > 0) out += ',';
    fmt::format_to(o, R"({{"time_ns":{},"kind":)", e.time_ns);
    append_string(out, e.kind);
    out += R"(,"detail":)";
    append_string(out, e.detail);
    out += '}';
  }
  out += "]}";
}

void SnapshotWriter::write_point(const live::LiveState& s, std::string& out) const {
  constexpr std::size_t kRoom = 512;
  if (out.capacity() < kRoom) out.reserve(kRoom);
  out.clear();
  auto o = std::back_inserter(out);
  fmt::format_to(o, R"({{"time_ns":{},"f2_n":{},"dr_mm":{},"fingertips":[)", s.now_ns,
                 control_.f2_n, control_.dr_mm);
  for (std::size_t i = 0; i < s.fingertips.size(); ++i) {
    const live::FingertipView& f = s.fingertips[i];
    if (i > 0) out += ',';
    out += R"({"id":)";
    append_string(out, f.id);
    fmt::format_to(o, R"(,"max_fz_n":{},"max_slip_mm":{}}})", finite(f.max_fz_n),
                   finite(f.max_slip_mm));
  }
  out += "]}";
}

}  // namespace tactile::web
