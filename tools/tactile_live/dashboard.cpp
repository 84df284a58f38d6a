#include "dashboard.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <iterator>
#include <numbers>
#include <optional>
#include <string_view>
#include <utility>

#include "tactile/control/types.hpp"
#include "tactile/wire/arm.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::live {
namespace {

constexpr std::int64_t kWindowNs = 1'000'000'000;

std::string strip(const std::string& name, std::string_view prefix) {
  return name.starts_with(prefix) ? name.substr(prefix.size()) : name;
}

bool twist_phase_named(const std::string& name) {
  const std::optional<control::Phase> phase = wire::phase_from_string(name);
  return phase && control::is_twist_phase(*phase);
}

std::string clock_text(std::int64_t ns, bool millis) {
  const std::time_t s = static_cast<std::time_t>(ns / 1'000'000'000);
  std::tm tm{};
  gmtime_r(&s, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%H:%M:%S", &tm);
  if (!millis) return buf;
  return fmt::format("{}.{:03d}", buf, static_cast<int>((ns / 1'000'000) % 1000));
}

// A line holding visible characters and, when colour is on, escape sequences that take no room.
class Line {
 public:
  Line(int width, bool color) : width_(width), color_(color) {}
  void text(std::string_view s, const char* sgr = nullptr) {
    if (used_ >= width_ || s.empty()) return;
    const auto n = std::min<std::size_t>(s.size(), static_cast<std::size_t>(width_ - used_));
    if (color_ && sgr != nullptr) out_ += fmt::format("\x1b[{}m", sgr);
    out_.append(s.substr(0, n));
    if (color_ && sgr != nullptr) out_ += "\x1b[0m";
    used_ += static_cast<int>(n);
  }
  void pad_to(int column) {
    if (column > used_) text(std::string(static_cast<std::size_t>(column - used_), ' '));
  }
  int used() const { return used_; }
  std::string take() {
    std::string s = std::move(out_);
    // No trailing blanks: the golden texts and a terminal's copy and paste stay clean.
    if (!color_) {
      while (!s.empty() && s.back() == ' ')
        s.pop_back();
    }
    out_.clear();
    used_ = 0;
    return s;
  }

 private:
  int width_;
  bool color_;
  std::string out_;
  int used_ = 0;
};

// One fingertip drawn as a block of lines of width `w`.
std::vector<std::string> fingertip_block(const FingertipView& f, const Calibration* cal, int w,
                                         int grid_rows, bool color, double f2) {
  std::vector<std::string> lines;
  Line l(w, color);
  l.text(f.id, "1");
  l.text(fmt::format(" seq {} {:.0f} fps", f.sequence, f.fps));
  if (f.lost > 0) l.text(fmt::format(" lost {}", f.lost), "33");
  if (f.status != "COMPLETE" && f.status != "-") l.text(" " + std::string(f.status), "33");
  if (f.age_s > 1.0) l.text(fmt::format(" stale {:.0f}s", f.age_s), "33");
  lines.push_back(l.take());
  if (f.decided) {
    l.text(f.touch ? "TOUCH" : "-----", f.touch ? "32" : "2");
    l.text(" ");
    l.text(f.slip ? "SLIP" : "----", f.slip ? "41;97" : "2");
    l.text(" ");
    l.text(f.over ? "OVER" : "----", f.over ? "41;97" : "2");
  } else {
    l.text("no decision", "2");
  }
  l.text(fmt::format(" Fz {:.2f}N d {:.4f}mm", f.max_fz_n, f.max_slip_mm));
  lines.push_back(l.take());
  if (f.has_stats) {
    l.text(fmt::format("camera {} frames, {} bad, measure {:.0f} us", f.camera_frames, f.incomplete,
                       f.measure_us_p50),
           "2");
  } else {
    l.text("no SensorStats yet", "2");
  }
  lines.push_back(l.take());
  if (grid_rows < 3 || f.elements.empty()) return lines;

  // The dome: each element one character at its place, two columns per unit of height so that
  // the rings look round in a terminal's tall character cells.
  const auto pos = dome_layout(f.elements.size(), cal);
  double minx = 1e300, maxx = -1e300, miny = 1e300, maxy = -1e300;
  for (const auto& p : pos) {
    minx = std::min(minx, p[0]);
    maxx = std::max(maxx, p[0]);
    miny = std::min(miny, p[1]);
    maxy = std::max(maxy, p[1]);
  }
  const int cols = std::max(3, std::min(w - 2, 2 * (grid_rows - 1) + 1));
  // A character cell is about twice as tall as wide: a unit across takes two columns per row.
  const double sx = std::min((cols - 1) / std::max(maxx - minx, 1e-9),
                             2.0 * (grid_rows - 1) / std::max(maxy - miny, 1e-9));
  const double sy = sx / 2.0;
  const int rows = std::min(grid_rows, static_cast<int>(std::lround((maxy - miny) * sy)) + 1);
  std::vector<std::string> cell(static_cast<std::size_t>(rows * cols));  // glyph per cell
  std::vector<const char*> sgr(static_cast<std::size_t>(rows * cols), nullptr);
  const double cx = (minx + maxx) / 2.0;
  const double cy = (miny + maxy) / 2.0;
  for (std::size_t i = 0; i < f.elements.size(); ++i) {
    int c = static_cast<int>(std::lround((pos[i][0] - cx) * sx + (cols - 1) / 2.0));
    int r = static_cast<int>(std::lround((pos[i][1] - cy) * sy + (rows - 1) / 2.0));
    c = std::clamp(c, 0, cols - 1);
    r = std::clamp(r, 0, rows - 1);
    // Taken: the nearest free cell along the row, then the rows around it.
    bool placed = false;
    for (int dr = 0; dr < rows && !placed; ++dr) {
      for (const int rr : {r + dr, r - dr}) {
        if (rr < 0 || rr >= rows || placed) continue;
        for (int dc = 0; dc < cols && !placed; ++dc) {
          for (const int cc : {c + dc, c - dc}) {
            if (cc < 0 || cc >= cols || placed) continue;
            auto& g = cell[static_cast<std::size_t>(rr * cols + cc)];
            if (!g.empty()) continue;
            const ElementCell& e = f.elements[i];
            if (!e.contact) {
              g = ".";
              sgr[static_cast<std::size_t>(rr * cols + cc)] = "2";
            } else if (e.fz_n > f2) {
              g = "#";
              sgr[static_cast<std::size_t>(rr * cols + cc)] = "1;31";
            } else {
              const int level = std::clamp(static_cast<int>(std::ceil(e.fz_n / f2 * 9.0)), 1, 9);
              g = std::to_string(level);
              sgr[static_cast<std::size_t>(rr * cols + cc)] = level >= 7 ? "33" : "32";
            }
            if (e.slip) {
              if (!color) g = "S";
              sgr[static_cast<std::size_t>(rr * cols + cc)] = "41;97";
            }
            placed = true;
          }
        }
      }
    }
  }
  for (int r = 0; r < rows; ++r) {
    l.text(" ");
    for (int c = 0; c < cols; ++c) {
      const auto& g = cell[static_cast<std::size_t>(r * cols + c)];
      l.text(g.empty() ? " " : g, sgr[static_cast<std::size_t>(r * cols + c)]);
    }
    lines.push_back(l.take());
  }
  return lines;
}

const Calibration* find_calibration(std::span<const Calibration> cals, const std::string& id) {
  for (const auto& c : cals) {
    if (c.sensor_id == id) return &c;
  }
  return nullptr;
}

}  // namespace

std::vector<std::array<double, 2>> dome_layout(std::size_t count, const Calibration* cal) {
  std::vector<std::array<double, 2>> out;
  if (cal != nullptr && cal->elements.size() == count) {
    for (const auto& e : cal->elements)
      out.push_back({e.center_px.x, e.center_px.y});
    return out;
  }
  std::size_t ring = 0;
  while (out.size() < count) {
    const std::size_t n = ring == 0 ? 1 : (ring == 1 ? 8 : 16 + 8 * ((ring - 2) / 2));
    const std::size_t take = std::min(n, count - out.size());
    for (std::size_t j = 0; j < take; ++j) {
      const double a = 2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(n);
      out.push_back(
          {static_cast<double>(ring) * std::cos(a), static_cast<double>(ring) * std::sin(a)});
    }
    ++ring;
  }
  return out;
}

ScreenLayout screen_layout(std::span<const FingertipView> fingertips, int width, int height,
                           int header_lines) {
  ScreenLayout out;
  for (std::size_t i = 0; i < fingertips.size(); ++i)
    out.order.push_back(i);
  const auto rank = [&](std::size_t i) {
    const std::string& id = fingertips[i].id;
    return std::pair(id == "left" ? 0 : (id == "right" ? 2 : 1), std::string_view(id));
  };
  std::stable_sort(out.order.begin(), out.order.end(),
                   [&](std::size_t a, std::size_t b) { return rank(a) < rank(b); });
  // Room: the header above; a legend, the events' title and at least one event below.
  const int fixed = header_lines + 3;
  const int block_rows = 3;  // a fingertip's summary lines above its dome
  const int n = std::max(static_cast<int>(fingertips.size()), 1);
  out.block_width = width / n;
  out.side_by_side = n == 1 || out.block_width >= 30;
  if (!out.side_by_side) out.block_width = width;
  const int rows =
      out.side_by_side ? height - fixed - block_rows - 1 : (height - fixed) / n - block_rows;
  // The dome is round: two columns per row, so a block's width bounds its rows; rows beyond
  // that go to the events.
  const int round = (out.block_width - 4) / 2 + 1;
  out.grid_rows = std::min(rows, round);
  if (out.grid_rows < 5) out.grid_rows = 0;  // too small a window: summaries only
  return out;
}

std::string event_line(const EventLine& e) {
  return fmt::format("{} {}{}{}", clock_text(e.time_ns, true), e.kind, e.detail.empty() ? "" : " ",
                     e.detail);
}

std::string render(const LiveState& s, std::span<const Calibration> cals, const RenderOptions& o) {
  const int width = std::max(o.width, 20);
  const int height = std::max(o.height, 5);
  std::vector<std::string> lines;
  Line l(width, o.color);
  l.text("tactile_live ", "1");
  l.text(clock_text(s.now_ns, false));
  l.text(fmt::format("  {} msgs", s.messages));
  if (s.undecodable > 0) l.text(fmt::format(", {} undecodable", s.undecodable), "33");
  lines.push_back(l.take());
  l.text("rates/s:");
  if (s.rates.empty()) l.text(" waiting for messages", "2");
  for (const auto& r : s.rates)
    l.text(fmt::format(" {} {:.1f}", r.topic, r.per_s));
  lines.push_back(l.take());
  l.text(fmt::format("phase {}", s.phase), "1");
  if (s.cycle > 0) l.text(fmt::format("  twist cycle {}", s.cycle));
  lines.push_back(l.take());
  std::string label;
  append_flags_label(s, label);
  l.text(label, s.flags_from == FlagSource::kNone ? "33" : nullptr);
  lines.push_back(l.take());

  const ScreenLayout layout =
      screen_layout(s.fingertips, width, height, static_cast<int>(lines.size()));
  const int n = static_cast<int>(s.fingertips.size());
  const int block_w = layout.block_width;
  const bool side_by_side = layout.side_by_side;
  const int grid_rows = layout.grid_rows;

  if (n == 0) {
    l.text("no TactileFrames yet", "2");
    lines.push_back(l.take());
  } else if (side_by_side) {
    std::vector<std::vector<std::string>> blocks;
    for (const std::size_t i : layout.order) {
      const FingertipView& f = s.fingertips[i];
      blocks.push_back(fingertip_block(f, find_calibration(cals, f.id), block_w - 2, grid_rows,
                                       o.color, o.f2_n));
    }
    std::size_t rows = 0;
    for (const auto& b : blocks)
      rows = std::max(rows, b.size());
    for (std::size_t r = 0; r < rows; ++r) {
      std::string joined;
      for (std::size_t b = 0; b < blocks.size(); ++b) {
        const std::string cell = r < blocks[b].size() ? blocks[b][r] : std::string();
        joined += cell;
        if (b + 1 < blocks.size()) {
          // Pad by visible width (escape sequences take no room).
          int visible = 0;
          for (std::size_t i = 0; i < cell.size(); ++i) {
            if (cell[i] == '\x1b') {
              while (i < cell.size() && cell[i] != 'm')
                ++i;
              continue;
            }
            ++visible;
          }
          joined.append(static_cast<std::size_t>(std::max(0, block_w - visible)), ' ');
        }
      }
      if (!o.color) {
        while (!joined.empty() && joined.back() == ' ')
          joined.pop_back();
      }
      lines.push_back(joined);
    }
  } else {
    for (const std::size_t i : layout.order) {
      const FingertipView& f = s.fingertips[i];
      for (auto& line :
           fingertip_block(f, find_calibration(cals, f.id), width, grid_rows, o.color, o.f2_n))
        lines.push_back(std::move(line));
    }
  }
  if (grid_rows > 0) {
    l.text(o.color ? ". none  1-9 F_z/F2  # over F2  red: slip"
                   : ". none  1-9 F_z in ninths of F2  # over F2  S slip",
           "2");
    lines.push_back(l.take());
  }
  l.text("events:", "1");
  if (s.events.empty()) l.text(" none yet", "2");
  lines.push_back(l.take());
  const int room = std::max(0, height - static_cast<int>(lines.size()));
  const std::size_t shown = std::min<std::size_t>(static_cast<std::size_t>(room), s.events.size());
  for (std::size_t i = s.events.size() - shown; i < s.events.size(); ++i) {
    l.text(" " + event_line(s.events[i]));
    lines.push_back(l.take());
  }
  if (static_cast<int>(lines.size()) > height) lines.resize(static_cast<std::size_t>(height));
  std::string out;
  for (const auto& line : lines) {
    out += line;
    out += '\n';
  }
  return out;
}

const char* to_string(FlagSource source) {
  switch (source) {
    case FlagSource::kHandNode:
      return "hand_node";
    case FlagSource::kRecomputed:
      return "recomputed";
    case FlagSource::kNone:
      break;
  }
  return "none";
}

void append_flags_label(const LiveState& s, std::string& out) {
  const std::string_view detector =
      s.detector.empty() ? std::string_view("detector not named") : std::string_view(s.detector);
  switch (s.flags_from) {
    case FlagSource::kHandNode:
      fmt::format_to(std::back_inserter(out), "flags: hand_node ({})", detector);
      return;
    case FlagSource::kRecomputed:
      fmt::format_to(std::back_inserter(out), "flags: recomputed ({})", detector);
      return;
    case FlagSource::kNone:
      break;
  }
  out += "flags: no decisions from hand_node (--recompute paper|field|learned decides here)";
}

std::string summary_lines(const LiveState& s) {
  std::string out;
  for (const auto& f : s.fingertips) {
    std::size_t contact = 0;
    for (const auto& e : f.elements)
      contact += e.contact ? 1 : 0;
    std::string flags;
    for (const auto& [on, name] :
         {std::pair{f.touch, "TOUCH"}, std::pair{f.slip, "SLIP"}, std::pair{f.over, "OVER"}}) {
      if (on) flags += flags.empty() ? name : std::string(",") + name;
    }
    std::string slipping;
    for (const auto& e : f.elements) {
      if (e.slip) slipping += fmt::format("{}{}", slipping.empty() ? "" : ",", e.id);
    }
    out += fmt::format(
        "{} {} seq={} fps={:.1f} lost={} status={} contact={}/{} max_fz={:.3f}N "
        "max_d={:.4f}mm flags={} slipping={} by={} detector={} phase={}\n",
        clock_text(s.now_ns, false), f.id, f.sequence, f.fps, f.lost, f.status, contact,
        f.elements.size(), f.max_fz_n, f.max_slip_mm,
        !f.decided ? "none" : (flags.empty() ? "-" : flags), slipping.empty() ? "-" : slipping,
        to_string(s.flags_from), s.detector.empty() ? "-" : s.detector, s.phase);
  }
  return out;
}

LiveModel::LiveModel(ModelOptions options, std::vector<std::string> endpoints)
    : options_(options), flags_(options_.control) {
  state_.endpoints = std::move(endpoints);
  if (options_.recompute) {
    state_.flags_from = FlagSource::kRecomputed;
    state_.detector = control::to_string(*options_.recompute);
  }
}

void LiveModel::on_frame(const v1::TactileFrame& fr, std::int64_t now) {
  std::size_t k = 0;
  FingertipView& f = fingertip(fr.sensor_id(), k);
  if (last_sequence_[k] && fr.sequence() > *last_sequence_[k] + 1)
    f.lost += fr.sequence() - *last_sequence_[k] - 1;
  last_sequence_[k] = fr.sequence();
  f.sequence = fr.sequence();
  // The enum's name is static: a view of it costs no allocation per frame.
  std::string_view status = v1::FrameStatus_Name(fr.status());
  if (status.starts_with("FRAME_STATUS_")) status.remove_prefix(13);
  f.status = status;
  last_frame_ns_[k] = now;
  if (fr.status() != v1::FRAME_STATUS_COMPLETE) return;
  if (wire::read_elements(fr, readings_) != wire::DecodeStatus::kOk) {
    ++state_.undecodable;
    return;
  }
  ++frame_counters_[k].count;
  f.elements.resize(readings_.size());
  for (std::size_t i = 0; i < readings_.size(); ++i) {
    const ElementReading& r = readings_[i];
    f.elements[i] = {r.id, r.contact, false, r.fz, r.fx, r.fy};
  }
  control::FingertipInput in;
  in.elements = readings_;
  in.fresh = true;
  // The frame's measurements (largest F_z and displacement in contact), whoever decides.
  const control::FingertipFlags measured = flags_.analyze(in, twist_phase_);
  f.max_fz_n = measured.max_fz_n;
  f.max_slip_mm = measured.max_slip_mm;
  if (options_.recompute) {
    const control::FingertipSlip& slip =
        detectors_[k].update(0, in, flags_.dr(twist_phase_), control::ArmMotion{});
    const control::FingertipFlags fl = flags_.analyze(in, slip);
    f.decided = true;
    f.touch = fl.touch;
    f.slip = fl.slip;
    f.over = fl.over;
    Slipping& s = slipping_[k];
    s.count = std::min<std::size_t>(fl.slipping_elements, s.ids.size());
    std::copy_n(fl.slipping_ids.begin(), s.count, s.ids.begin());
  }
  mark_slipping(k);
}

void LiveModel::on_decision(const v1::Decision& d) {
  if (options_.recompute) return;  // asked to decide here: hand_node's decisions are not shown
  state_.flags_from = FlagSource::kHandNode;
  if (state_.detector != d.slip_detector()) state_.detector = d.slip_detector();
  for (const v1::FingertipDecision& t : d.fingertips()) {
    std::size_t k = 0;
    FingertipView& f = fingertip(t.sensor_id(), k);
    f.decided = true;
    f.touch = t.touch();
    f.slip = t.slip();
    f.over = t.over();
    Slipping& s = slipping_[k];
    s.count = std::min<std::size_t>(static_cast<std::size_t>(t.slipping_element_ids_size()),
                                    s.ids.size());
    std::copy_n(t.slipping_element_ids().begin(), s.count, s.ids.begin());
    mark_slipping(k);
  }
}

void LiveModel::mark_slipping(std::size_t k) {
  const Slipping& s = slipping_[k];
  const auto named = [&](std::uint32_t id) {
    return std::find(s.ids.begin(), s.ids.begin() + static_cast<std::ptrdiff_t>(s.count), id) !=
           s.ids.begin() + static_cast<std::ptrdiff_t>(s.count);
  };
  for (ElementCell& e : state_.fingertips[k].elements)
    e.slip = named(e.id);
}

FingertipView& LiveModel::fingertip(const std::string& id, std::size_t& index) {
  for (index = 0; index < state_.fingertips.size(); ++index) {
    if (state_.fingertips[index].id == id) return state_.fingertips[index];
  }
  FingertipView f;
  f.id = id;
  state_.fingertips.push_back(std::move(f));
  frame_counters_.push_back(Counter{id});
  last_frame_ns_.push_back(0);
  last_sequence_.emplace_back();
  slipping_.emplace_back();
  if (options_.recompute) detectors_.emplace_back(*options_.recompute, options_.control);
  index = state_.fingertips.size() - 1;
  return state_.fingertips.back();
}

void LiveModel::count(std::string_view topic, std::int64_t now) {
  for (auto& c : counters_) {
    if (c.topic == topic) {
      ++c.count;
      return;
    }
  }
  Counter c{std::string(topic)};
  c.count = 1;
  c.since_ns = now;
  counters_.push_back(std::move(c));
}

int LiveModel::add(std::string_view topic, std::span<const std::uint8_t> payload,
                   std::int64_t now) {
  ++state_.messages;
  count(topic, now);
  if (decoder_.decode(payload) != wire::DecodeStatus::kOk) {
    ++state_.undecodable;
    return -1;
  }
  const v1::Envelope& envelope = decoder_.envelope();
  std::size_t k = 0;
  switch (envelope.body_case()) {
    case v1::Envelope::kTactileFrame:
      on_frame(envelope.tactile_frame(), now);
      break;
    case v1::Envelope::kDecision:
      on_decision(envelope.decision());
      break;
    case v1::Envelope::kSensorStats: {
      const v1::SensorStats& st = envelope.sensor_stats();
      FingertipView& f = fingertip(st.sensor_id(), k);
      f.has_stats = true;
      f.camera_frames = st.frames();
      f.incomplete = st.frames_incomplete();
      f.measure_us_p50 = st.measure_us_p50();
      break;
    }
    case v1::Envelope::kEvent: {
      const v1::Event& e = envelope.event();
      if (!e.phase().empty()) {
        state_.phase = e.phase();
        twist_phase_ = twist_phase_named(e.phase());
      }
      if (e.kind() == v1::EVENT_KIND_TWIST_CYCLE || e.kind() == v1::EVENT_KIND_CAP_TIGHT)
        state_.cycle = e.cycle();
      EventLine line;
      line.time_ns = e.time_ns();
      line.kind = strip(v1::EventKind_Name(e.kind()), "EVENT_KIND_");
      std::string d;
      if (!e.sensor_id().empty()) d += fmt::format("{} e{} ", e.sensor_id(), e.element_id());
      if (e.value() != 0) d += fmt::format("{:.4g} ", e.value());
      if (e.cycle() != 0) d += fmt::format("cycle {} ", e.cycle());
      d += e.text();
      while (!d.empty() && d.back() == ' ')
        d.pop_back();
      line.detail = std::move(d);
      state_.events.push_back(std::move(line));
      ++state_.events_total;
      while (state_.events.size() > options_.max_events)
        state_.events.pop_front();
      return static_cast<int>(state_.events.size()) - 1;
    }
    default:
      break;
  }
  return -1;
}

void LiveModel::tick(std::int64_t now, std::int64_t now_real) {
  state_.now_ns = now_real;
  auto roll = [now](Counter& c) {
    const std::int64_t span = now - c.since_ns;
    if (span >= kWindowNs) {
      c.rate = static_cast<double>(c.count) * 1e9 / static_cast<double>(span);
      c.count = 0;
      c.since_ns = now;
    }
  };
  state_.rates.resize(counters_.size());
  for (std::size_t i = 0; i < counters_.size(); ++i) {
    roll(counters_[i]);
    state_.rates[i].topic = counters_[i].topic;
    state_.rates[i].per_s = counters_[i].rate;
  }
  for (std::size_t i = 0; i < frame_counters_.size(); ++i) {
    if (frame_counters_[i].since_ns == 0) frame_counters_[i].since_ns = now;
    roll(frame_counters_[i]);
    state_.fingertips[i].fps = frame_counters_[i].rate;
    state_.fingertips[i].age_s = static_cast<double>(now - last_frame_ns_[i]) * 1e-9;
  }
}

}  // namespace tactile::live
