#include "plot_data.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "tactile/control/types.hpp"
#include "tactile/plot/figure.hpp"
#include "tactile/plot/task_figures.hpp"
#include "tactile/wire/arm.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/tactile_frame.hpp"

namespace tactile::plots {
namespace {

bool twist_phase_named(const std::string& name) {
  const std::optional<control::Phase> phase = wire::phase_from_string(name);
  return phase && control::is_twist_phase(*phase);
}

std::string event_name(v1::EventKind k) {
  std::string n = v1::EventKind_Name(k);
  const std::string prefix = "EVENT_KIND_";
  return n.starts_with(prefix) ? n.substr(prefix.size()) : n;
}

std::string safe(const std::string& id) {
  std::string s;
  for (const char c : id)
    s += std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_' ? c : '_';
  return s;
}

}  // namespace

PlotData::PlotData(PlotOptions options) : options_(std::move(options)), flags_(options_.control) {
  for (const auto& c : options_.calibrations) {
    SensorData* s = sensor(c.sensor_id);
    if (s == nullptr) continue;
    for (const auto& e : c.elements)
      s->positions[e.id] = {e.center_px.x * c.mm_per_px, e.center_px.y * c.mm_per_px};
  }
}

SensorData* PlotData::sensor(const std::string& id) {
  for (auto& s : sensors_) {
    if (s.id == id) return &s;
  }
  if (!options_.sensors.empty() &&
      std::find(options_.sensors.begin(), options_.sensors.end(), id) == options_.sensors.end()) {
    return nullptr;
  }
  if (options_.recompute) detectors_.emplace_back(*options_.recompute, options_.control);
  SensorData s;
  s.id = id;
  if (options_.at_s.empty()) {
    s.snapshots.push_back(Snapshot{});
  } else {
    for (const double t : options_.at_s) {
      Snapshot snap;
      snap.target_s = t;
      snap.score = -std::numeric_limits<double>::infinity();
      s.snapshots.push_back(snap);
    }
  }
  sensors_.push_back(std::move(s));
  return &sensors_.back();
}

FlagSource PlotData::flag_source() const {
  if (options_.recompute) return FlagSource::kRecomputed;
  return decisions_ ? FlagSource::kHandNode : FlagSource::kNone;
}

std::string PlotData::flag_source_text() const {
  switch (flag_source()) {
    case FlagSource::kHandNode:
      return fmt::format("flags: hand_node ({})",
                         detector_.empty() ? "detector not named" : detector_);
    case FlagSource::kRecomputed:
      return fmt::format("flags: recomputed ({})", control::to_string(*options_.recompute));
    case FlagSource::kNone:
      break;
  }
  return "no hand_node decisions in the log: no flags (--recompute paper|field|learned)";
}

// hand_node's decision on the frames it answered: each answered frame's sample takes its
// fingertip's flags (frames are recorded before the decisions that answer them).
void PlotData::on_decision(const v1::Decision& d) {
  decisions_ = true;
  detector_ = d.slip_detector();
  if (options_.recompute) return;
  for (const v1::FrameRef& ref : d.answers()) {
    SensorData* s = sensor(ref.sensor_id());
    if (s == nullptr) continue;
    const auto tip = std::find_if(
        d.fingertips().begin(), d.fingertips().end(),
        [&](const v1::FingertipDecision& t) { return t.sensor_id() == ref.sensor_id(); });
    if (tip == d.fingertips().end()) continue;
    for (auto it = s->frames.rbegin(); it != s->frames.rend(); ++it) {
      if (it->sequence != ref.sequence()) continue;
      it->decided = true;
      it->touch = tip->touch();
      it->slip = tip->slip();
      it->over = tip->over();
      break;
    }
  }
}

std::string PlotData::position_source_text() const {
  switch (source_) {
    case PositionSource::kArmState:
      return "ArmState: wrist + the fingertip's position rotated by the wrist yaw, along the "
             "transport (first to last touch)";
    case PositionSource::kGroundTruth:
      return "GroundTruth object_position_m: the cap held between the fingertips, along the "
             "transport (first to last touch)";
    case PositionSource::kNone:
      break;
  }
  return "none in the log (no ArmState or GroundTruth): plotted against time instead";
}

void PlotData::add(const v1::LogRecord& record) {
  if (!first_ns_) first_ns_ = record.receive_time_ns();
  if (record.kind() != v1::PAYLOAD_KIND_ENVELOPE) return;
  if (wire::decode(wire::bytes_of(record.payload()), envelope_) != wire::DecodeStatus::kOk) return;
  const double t = static_cast<double>(record.receive_time_ns() - *first_ns_) * 1e-9;
  switch (envelope_.body_case()) {
    case v1::Envelope::kTactileFrame:
      on_frame(envelope_.tactile_frame(), t, record.receive_time_ns());
      break;
    case v1::Envelope::kDecision:
      on_decision(envelope_.decision());
      break;
    case v1::Envelope::kEvent: {
      const v1::Event& e = envelope_.event();
      if (e.kind() == v1::EVENT_KIND_PHASE) twist_phase_ = twist_phase_named(e.phase());
      events_.push_back({t, event_name(e.kind()), e.text(), e.cycle()});
      break;
    }
    case v1::Envelope::kGroundTruth:
      if (source_ != PositionSource::kArmState) {
        source_ = PositionSource::kGroundTruth;
        truth_x_mm_ = envelope_.ground_truth().object_position_m().x() * 1000.0;
        truth_y_mm_ = envelope_.ground_truth().object_position_m().y() * 1000.0;
      }
      break;
    case v1::Envelope::kArmState: {
      source_ = PositionSource::kArmState;
      const v1::ArmState& a = envelope_.arm_state();
      const double c = std::cos(a.wrist().yaw_rad());
      const double s = std::sin(a.wrist().yaw_rad());
      for (const auto& f : a.fingertips()) {
        arm_xy_mm_[f.sensor_id()] = {
            (a.wrist().position_m().x() + c * f.position_m().x() - s * f.position_m().y()) * 1000.0,
            (a.wrist().position_m().y() + s * f.position_m().x() + c * f.position_m().y()) *
                1000.0};
      }
      break;
    }
    default:
      break;
  }
}

void PlotData::on_frame(const v1::TactileFrame& f, double t, std::int64_t receive_ns) {
  SensorData* s = sensor(f.sensor_id());
  if (s == nullptr) return;
  FrameSample x;
  x.t_s = t;
  x.sequence = f.sequence();
  // Until a Decision answers this frame: the fingertip's latest TOUCH and OVER held.
  if (!s->frames.empty()) {
    x.touch = s->frames.back().touch;
    x.over = s->frames.back().over;
  }
  if (f.publish_timestamp_ns() > 0) {
    const double cam =
        static_cast<double>(f.publish_timestamp_ns() - f.camera_timestamp_ns()) * 1e-6;
    // A camera with its own clock gives no meaningful difference: keep only plausible ones.
    if (f.camera_timestamp_ns() > 0 && cam >= 0 && cam < 10'000) x.camera_to_publish_ms = cam;
    if (f.receive_timestamp_ns() > 0) {
      x.receive_to_publish_ms =
          static_cast<double>(f.publish_timestamp_ns() - f.receive_timestamp_ns()) * 1e-6;
    }
    x.publish_to_record_ms = static_cast<double>(receive_ns - f.publish_timestamp_ns()) * 1e-6;
  }
  if (f.status() != v1::FRAME_STATUS_COMPLETE) {
    ++s->incomplete;
    s->frames.push_back(x);
    return;
  }
  if (wire::read_elements(f, readings_) != wire::DecodeStatus::kOk) {
    ++s->incomplete;  // not usable whole: counted with the incomplete frames
    s->frames.push_back(x);
    return;
  }
  double dy_of_max = 0;
  double best = -1;
  for (const v1::ElementReading& e : f.elements()) {
    if (e.contact()) {
      s->centroid_sum[e.id()].first += e.x_mm();
      s->centroid_sum[e.id()].second += e.y_mm();
      ++s->centroid_count[e.id()];
      x.max_fz_n = std::max(x.max_fz_n, e.fz_n());
      const double d = std::hypot(e.dx_mm(), e.dy_mm());
      if (e.has_displacement() && d > best) {
        best = d;
        dy_of_max = e.dy_mm();
      }
    }
    if (options_.element && e.id() == *options_.element) dy_of_max = e.dy_mm();
  }
  control::FingertipInput in;
  in.elements = readings_;
  in.fresh = true;
  // The frame's largest displacement in contact, whoever decides.
  x.max_slip_mm = flags_.analyze(in, twist_phase_).max_slip_mm;
  if (options_.recompute) {
    control::SlipDetector& detector = detectors_[static_cast<std::size_t>(s - sensors_.data())];
    const control::FingertipFlags fl =
        flags_.analyze(in, detector.update(0, in, flags_.dr(twist_phase_), control::ArmMotion{}));
    x.decided = true;
    x.touch = fl.touch;
    x.slip = fl.slip;
    x.over = fl.over;
  }
  x.dy_mm = dy_of_max;
  if (source_ == PositionSource::kArmState) {
    const auto it = arm_xy_mm_.find(f.sensor_id());
    if (it != arm_xy_mm_.end()) {
      x.world_x_mm = it->second.first;
      x.world_y_mm = it->second.second;
    }
  } else if (source_ == PositionSource::kGroundTruth) {
    x.world_x_mm = truth_x_mm_;
    x.world_y_mm = truth_y_mm_;
  }
  if (s->element_ids.size() != static_cast<std::size_t>(f.elements_size())) {
    s->element_ids.clear();
    for (const auto& e : f.elements())
      s->element_ids.push_back(e.id());
  }
  s->frames.push_back(x);
  snapshot(*s, f, t);
}

void PlotData::snapshot(SensorData& s, const v1::TactileFrame& f, double t) {
  double shear = 0;
  for (const auto& e : f.elements())
    shear += std::hypot(e.ux_mm(), e.uy_mm());
  for (Snapshot& snap : s.snapshots) {
    const double score = std::isnan(snap.target_s) ? shear : -std::abs(t - snap.target_s);
    if (score <= snap.score) continue;
    snap.score = score;
    snap.t_s = t;
    snap.sequence = f.sequence();
    snap.elements.clear();
    for (const auto& e : f.elements()) {
      snap.elements.push_back({e.id(), e.contact(), e.x_mm(), e.y_mm(), e.ux_mm(), e.uy_mm(),
                               e.fx_n(), e.fy_n(), e.fz_n()});
    }
  }
}

void PlotData::finish() {
  for (auto& s : sensors_) {
    // The transport: from where this fingertip first touched (the cap's place) to where it last
    // touched (the bottle), horizontally; Fig. 10's x is the position along it (the rig's
    // definition, docs/rig.md "Scoring").
    const FrameSample* first = nullptr;
    const FrameSample* last = nullptr;
    for (const FrameSample& f : s.frames) {
      if (!f.touch || std::isnan(f.world_x_mm)) continue;
      if (first == nullptr) first = &f;
      last = &f;
    }
    if (first != nullptr) {
      const double dx = last->world_x_mm - first->world_x_mm;
      const double dy = last->world_y_mm - first->world_y_mm;
      const double n = std::hypot(dx, dy);
      if (n >= 1.0) {
        s.transport_x = dx / n;
        s.transport_y = dy / n;
        s.transport_known = true;
      }
    }
    for (FrameSample& f : s.frames)
      f.x_mm = f.world_x_mm * s.transport_x + f.world_y_mm * s.transport_y;
    for (const auto& [id, sum] : s.centroid_sum) {
      if (s.positions.count(id) != 0) continue;
      const double n = s.centroid_count[id];
      s.positions[id] = {sum.first / n, sum.second / n};
    }
  }
}

std::optional<std::pair<double, double>> PlotData::frame_time_range() const {
  std::optional<std::pair<double, double>> r;
  for (const auto& s : sensors_) {
    for (const auto& f : s.frames) {
      if (!r) r = std::pair{f.t_s, f.t_s};
      r->first = std::min(r->first, f.t_s);
      r->second = std::max(r->second, f.t_s);
    }
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// Figures

namespace {

// Element spacing: the median distance to the nearest other element (for arrow scales).
double spacing(const SensorData& s) {
  std::vector<double> nearest;
  for (const auto& [a, pa] : s.positions) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& [b, pb] : s.positions) {
      if (a != b) best = std::min(best, std::hypot(pa.first - pb.first, pa.second - pb.second));
    }
    if (std::isfinite(best)) nearest.push_back(best);
  }
  if (nearest.empty()) return 1.0;
  std::nth_element(nearest.begin(),
                   nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2),
                   nearest.end());
  return nearest[nearest.size() / 2];
}

// The axes of a map of the fingertip, drawn with -y up: the elements' layout and one element
// spacing around it, so the fingertip fills the panel (an arrow reaching beyond is cut at the
// edge).
std::pair<std::pair<double, double>, std::pair<double, double>> layout_ranges(const SensorData& s) {
  double x_lo = std::numeric_limits<double>::infinity();
  double x_hi = -x_lo;
  double y_lo = x_lo;
  double y_hi = -x_lo;
  for (const auto& [id, pos] : s.positions) {
    x_lo = std::min(x_lo, pos.first);
    x_hi = std::max(x_hi, pos.first);
    y_lo = std::min(y_lo, -pos.second);
    y_hi = std::max(y_hi, -pos.second);
  }
  const double margin = spacing(s);
  return {{x_lo - margin, x_hi + margin}, {y_lo - margin, y_hi + margin}};
}

std::string snapshot_title(const Snapshot& snap) {
  if (std::isnan(snap.target_s)) return fmt::format("t = {:.3f} s (largest total shear)", snap.t_s);
  return fmt::format("t = {:.3f} s (asked {:.3f} s)", snap.t_s, snap.target_s);
}

// Element positions drawn with -y up, so the picture looks like the camera image.
// Returns how many elements of the frames could not be placed (never in contact and no
// --calibration), for the panel's title.
std::size_t element_dots(plot::Panel& p, const SensorData& s, const Snapshot& snap) {
  std::vector<double> ox, oy, cx, cy;
  for (const auto& [id, pos] : s.positions) {
    bool contact = false;
    for (const auto& e : snap.elements) {
      if (e.id == id) contact = e.contact;
    }
    (contact ? cx : ox).push_back(pos.first);
    (contact ? cy : oy).push_back(-pos.second);
  }
  plot::Style grey;
  grey.color = plot::kGray;
  grey.marker_radius = 3;
  p.scatter(ox, oy, "out of contact", grey);
  plot::Style black;
  black.color = plot::kBlack;
  black.marker_radius = 3;
  p.scatter(cx, cy, "in contact", black);
  return static_cast<std::size_t>(
      std::count_if(s.element_ids.begin(), s.element_ids.end(),
                    [&](std::uint32_t id) { return s.positions.count(id) == 0; }));
}

std::string unplaced_text(std::size_t n) {
  if (n == 0) return {};
  return fmt::format("; {} never in contact, not placed (give --calibration)", n);
}

}  // namespace

std::vector<std::filesystem::path> draw_shear_fields(const PlotData& d,
                                                     const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> out;
  for (const auto& s : d.sensors()) {
    if (s.positions.empty()) continue;
    plot::Figure fig(d.options().width,
                     std::max(d.options().height / 2, 320) * static_cast<int>(s.snapshots.size()));
    fig.title(fmt::format("Shear displacement field, fingertip {} (Fig. 3)", s.id));
    double umax = 0;
    for (const auto& snap : s.snapshots) {
      for (const auto& e : snap.elements)
        umax = std::max(umax, std::hypot(e.ux_mm, e.uy_mm));
    }
    const double scale = umax > 0 ? 0.8 * spacing(s) / umax : 1.0;
    const auto [x_range, y_range] = layout_ranges(s);
    for (const auto& snap : s.snapshots) {
      auto& p = fig.add_panel();
      p.x_label("x [mm]").y_label("-y [mm] (up in the image)").equal_aspect();
      p.x_range(x_range.first, x_range.second).y_range(y_range.first, y_range.second);
      const std::size_t unplaced = element_dots(p, s, snap);
      p.title(fmt::format("{}; arrows: u (mm) x {:.3g}{}", snapshot_title(snap), scale,
                          unplaced_text(unplaced)));
      std::vector<double> x, y, u, v;
      for (const auto& e : snap.elements) {
        if (!e.contact) continue;
        const auto it = s.positions.find(e.id);
        if (it == s.positions.end()) continue;
        x.push_back(it->second.first);
        y.push_back(-it->second.second);
        u.push_back(e.ux_mm);
        v.push_back(-e.uy_mm);
      }
      plot::Style st;
      st.arrow_scale = scale;
      st.color = plot::palette(3);
      p.arrows(x, y, u, v, "shear displacement u", st);
    }
    fig.fit_height_to_aspect();
    out.push_back(dir / ("shear_" + safe(s.id) + ".png"));
    fig.save_png(out.back());
  }
  return out;
}

std::vector<std::filesystem::path> draw_force_maps(const PlotData& d,
                                                   const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> out;
  // Normal force in five bands, light to dark; shear force as arrows.
  const plot::Color band_colors[] = {
      {198, 219, 239}, {107, 174, 214}, {33, 113, 181}, {239, 101, 72}, {165, 15, 21}};
  for (const auto& s : d.sensors()) {
    if (s.positions.empty()) continue;
    plot::Figure fig(d.options().width,
                     std::max(d.options().height / 2, 320) * static_cast<int>(s.snapshots.size()));
    fig.title(fmt::format("Element forces, fingertip {}", s.id));
    double fmax = 0;
    double smax = 0;
    for (const auto& snap : s.snapshots) {
      for (const auto& e : snap.elements) {
        fmax = std::max(fmax, e.fz_n);
        smax = std::max(smax, std::hypot(e.fx_n, e.fy_n));
      }
    }
    const double top = fmax > 0 ? fmax : 1.0;
    const double scale = smax > 0 ? 0.8 * spacing(s) / smax : 1.0;
    for (const auto& snap : s.snapshots) {
      auto& p = fig.add_panel();
      p.title(fmt::format("{}; arrows: (F_x, F_y) N x {:.3g}", snapshot_title(snap), scale))
          .x_label("x [mm]")
          .y_label("-y [mm] (up in the image)")
          .equal_aspect();
      std::vector<double> bx[5], by[5];
      std::vector<double> ax, ay, au, av;
      for (const auto& e : snap.elements) {
        const auto it = s.positions.find(e.id);
        if (it == s.positions.end()) continue;
        const int band = std::clamp(static_cast<int>(e.fz_n / top * 5.0), 0, 4);
        bx[band].push_back(it->second.first);
        by[band].push_back(-it->second.second);
        if (e.contact) {
          ax.push_back(it->second.first);
          ay.push_back(-it->second.second);
          au.push_back(e.fx_n);
          av.push_back(-e.fy_n);
        }
      }
      for (int b = 0; b < 5; ++b) {
        plot::Style st;
        st.color = band_colors[b];
        st.marker_radius = 4 + 2 * b;
        p.scatter(bx[b], by[b], fmt::format("F_z {:.2f}-{:.2f} N", top * b / 5, top * (b + 1) / 5),
                  st);
      }
      plot::Style arrow;
      arrow.arrow_scale = scale;
      arrow.color = plot::kBlack;
      p.arrows(ax, ay, au, av, "shear force", arrow);
    }
    out.push_back(dir / ("forces_" + safe(s.id) + ".png"));
    fig.save_png(out.back());
  }
  return out;
}

namespace {

// The recording as the task figures take it (the same figures the rig draws of its runs).
plot::TaskFigureInput task_input(const PlotData& d) {
  plot::TaskFigureInput in;
  const control::Config& cfg = d.options().control;
  in.f1_n = cfg.f1_n;
  in.f2_n = cfg.f2_n;
  in.dr_mm = cfg.dr_mm;
  in.twist_dr_factor = cfg.twist_dr_factor;
  switch (d.position_source()) {
    case PositionSource::kArmState:
      in.x_source = "from ArmState";
      break;
    case PositionSource::kGroundTruth:
      in.x_source = "from GroundTruth, the held cap";
      break;
    case PositionSource::kNone:
      in.x_is_time = true;
      break;
  }
  in.title = d.flag_source_text();
  for (const auto& s : d.sensors()) {
    if (d.position_source() != PositionSource::kNone && !s.transport_known)
      in.x_source += "; world x: no transport seen";
    plot::FingertipTrace f;
    f.name = s.id;
    for (const auto& x : s.frames) {
      f.t_s.push_back(x.t_s);
      f.x_mm.push_back(in.x_is_time ? x.t_s : x.x_mm);
      f.dy_mm.push_back(x.dy_mm);
      f.max_fz_n.push_back(x.max_fz_n);
      f.touch.push_back(x.touch ? 1 : 0);
      f.slip.push_back(x.slip ? 1 : 0);
      f.over.push_back(x.over ? 1 : 0);
    }
    in.fingertips.push_back(std::move(f));
  }
  for (const auto& e : d.events()) {
    if (auto text = plot::task_event_label(e.kind, e.cycle)) in.events.push_back({e.t_s, *text});
  }
  return in;
}

}  // namespace

std::vector<std::filesystem::path> draw_fig10(const PlotData& d, const std::filesystem::path& dir) {
  if (d.sensors().empty()) return {};
  const auto path = dir / "fig10.png";
  plot::fig10(task_input(d), d.options().width, d.options().height).save_png(path);
  return {path};
}

std::vector<std::filesystem::path> draw_timeline(const PlotData& d,
                                                 const std::filesystem::path& dir) {
  if (d.sensors().empty()) return {};
  const auto path = dir / "timeline.png";
  plot::timeline(task_input(d), d.options().width, d.options().height).save_png(path);
  return {path};
}

std::vector<std::filesystem::path> draw_latency(const PlotData& d,
                                                const std::filesystem::path& dir) {
  if (d.sensors().empty()) return {};
  plot::Figure fig(d.options().width, d.options().height);
  fig.title("Latency histograms");
  auto& cam = fig.add_panel();
  auto& pub = fig.add_panel();
  auto& net = fig.add_panel();
  cam.title("camera timestamp -> publish (sensor_node)").x_label("ms").y_label("frames");
  pub.title("frame received -> publish (sensor_node)").x_label("ms").y_label("frames");
  net.title("publish -> received by the recorder").x_label("ms").y_label("frames");
  bool any_camera = false;
  for (const auto& s : d.sensors()) {
    std::vector<double> a, b, c;
    for (const auto& f : s.frames) {
      if (!std::isnan(f.camera_to_publish_ms)) a.push_back(f.camera_to_publish_ms);
      if (!std::isnan(f.receive_to_publish_ms)) b.push_back(f.receive_to_publish_ms);
      if (!std::isnan(f.publish_to_record_ms)) c.push_back(f.publish_to_record_ms);
    }
    any_camera = any_camera || !a.empty();
    // The bulk of each: a pause of the machine is counted at the edge, not binned.
    const plot::RobustRange bulk{0.0, 0.95, 0.5};
    cam.histogram(a, 40, bulk, s.id);
    pub.histogram(b, 40, bulk, s.id);
    net.histogram(c, 40, bulk, s.id);
  }
  if (!any_camera)
    cam.title("camera timestamp -> publish: no camera timestamps on this host's clock");
  const auto path = dir / "latency.png";
  fig.save_png(path);
  return {path};
}

}  // namespace tactile::plots
