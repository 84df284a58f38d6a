#include "tactile/extractor.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "disk.hpp"
#include "kernels.hpp"

namespace tactile {
namespace {

// Increments and weights are fixed point with 8 fractional bits (Q8): the reference mean of N
// frames keeps sub-gray-level precision and every sum stays an exact 64-bit integer.
constexpr int kQBits = 8;
constexpr double kQ = 256.0;

template <typename Pixel>
constexpr std::int32_t q8(Pixel p) {
  return static_cast<std::int32_t>(p) << kQBits;
}

// ceil and floor for values well inside the int range, without a library call (the baseline
// x86-64 build has no rounding instruction).
int ceil_int(double v) {
  const int i = static_cast<int>(v);
  return i < v ? i + 1 : i;
}
int floor_int(double v) {
  const int i = static_cast<int>(v);
  return i > v ? i - 1 : i;
}

// kGaussianAxes: a width that changed by more than this fraction on the first pass gets a
// second one.
constexpr double kAxesRepassChange = 0.1;

double soft_edge(double half_width, double distance) {
  return std::clamp(half_width + 0.5 - std::abs(distance), 0.0, 1.0);
}

}  // namespace

const char* to_string(CentroidEstimator e) {
  switch (e) {
    case CentroidEstimator::kPlain:
      return "plain";
    case CentroidEstimator::kThresholded:
      return "thresholded";
    case CentroidEstimator::kWindowed:
      return "windowed";
    case CentroidEstimator::kGaussian:
      return "gaussian";
    case CentroidEstimator::kGaussianAxes:
      return "gaussian-axes";
  }
  return "unknown";
}

std::optional<CentroidEstimator> parse_estimator(std::string_view name) {
  for (auto e :
       {CentroidEstimator::kPlain, CentroidEstimator::kThresholded, CentroidEstimator::kWindowed,
        CentroidEstimator::kGaussian, CentroidEstimator::kGaussianAxes}) {
    if (name == to_string(e)) return e;
  }
  return std::nullopt;
}

const char* to_string(MeasureStatus s) {
  switch (s) {
    case MeasureStatus::kOk:
      return "ok";
    case MeasureStatus::kNoReference:
      return "no reference";
    case MeasureStatus::kWrongSize:
      return "frame size differs from the calibration";
    case MeasureStatus::kWrongFormat:
      return "pixel format differs from the calibration";
  }
  return "unknown";
}

const char* to_string(ReferenceStatus s) {
  switch (s) {
    case ReferenceStatus::kCollecting:
      return "collecting";
    case ReferenceStatus::kComplete:
      return "complete";
    case ReferenceStatus::kRefusedMotion:
      return "refused: a frame changed while capturing (the sensor is being touched)";
    case ReferenceStatus::kRefusedLoad:
      return "refused: the sensor is loaded (against the previous reference)";
    case ReferenceStatus::kRefusedSpot:
      return "refused: an element shows a contact spot";
    case ReferenceStatus::kWrongSize:
      return "refused: frame size differs from the calibration";
    case ReferenceStatus::kWrongFormat:
      return "refused: pixel format differs from the calibration";
    case ReferenceStatus::kNoFrames:
      return "refused: no frames";
  }
  return "unknown";
}

Extractor::Extractor(Calibration cal, ExtractorOptions options)
    : cal_(std::move(cal)), opt_(options) {
  validate(cal_);
  if (opt_.reference_frames < 1 || opt_.reference_frames > 65536) {
    throw std::invalid_argument("reference_frames must be 1..65536, is " +
                                std::to_string(opt_.reference_frames));
  }
  if (opt_.max_gap_frames < 1) throw std::invalid_argument("max_gap_frames must be at least 1");
  if (!std::isfinite(opt_.window_margin_px) || opt_.window_margin_px < 0) {
    throw std::invalid_argument("window_margin_px must be a non-negative number");
  }
  if (!std::isfinite(opt_.gaussian_reach_sigmas) || opt_.gaussian_reach_sigmas < 1) {
    throw std::invalid_argument("gaussian_reach_sigmas must be at least 1");
  }
  floor_q_ = static_cast<std::int32_t>(std::lround(cal_.noise_floor * kQ));

  std::uint32_t offset = 0;
  layout_.reserve(cal_.elements.size());
  for (const ElementCalibration& e : cal_.elements) {
    ElementLayout el{};
    el.span_begin = static_cast<std::uint32_t>(spans_.size());
    el.origin_x = std::numeric_limits<std::int32_t>::max();
    for_each_disk_row(e.center_px, e.radius_px, [&](int y, int x0, int x1) {
      spans_.push_back({y, x0, x1, offset});
      offset += static_cast<std::uint32_t>(x1 - x0);
      el.origin_x = std::min(el.origin_x, x0);
    });
    el.span_end = static_cast<std::uint32_t>(spans_.size());
    el.origin_y = spans_[el.span_begin].y;
    layout_.push_back(el);
  }
  ref_q_.assign(offset, 0);

  kernels_ = opt_.portable_kernels ? &detail::portable_kernels() : &detail::best_kernels();
  disks_ = region_of_interest(cal_);
  // Blocks: each disk's bounding box widened to a multiple of 32 columns (one AVX2 vector of
  // 8-bit pixels), kept inside the region of all disks so that a region-of-interest frame holds
  // every block too.
  std::uint32_t block_offset = 0;
  for (const ElementLayout& el : layout_) {
    int x1 = el.origin_x;
    for (std::uint32_t k = el.span_begin; k < el.span_end; ++k)
      x1 = std::max(x1, spans_[k].x1);
    const int width = x1 - el.origin_x;
    const int padded = std::min((width + 31) / 32 * 32, disks_.width);
    const int x0 = std::min(el.origin_x, disks_.x + disks_.width - padded);
    const int height = static_cast<int>(el.span_end - el.span_begin);
    blocks_.push_back({x0, el.origin_y, padded, height, block_offset});
    block_offset += static_cast<std::uint32_t>(padded * height);
  }
  int max_side = 1;
  for (const detail::Block& b : blocks_)
    max_side = std::max({max_side, b.width, b.height});
  // The Gaussian kernels' scratch: block columns with kGaussPad either side, window rows with
  // kGaussPad after them.
  wx_.assign(static_cast<std::size_t>(max_side + 2 * detail::kGaussPad), 0.0F);
  wxu_ = wx_;
  wxu2_ = wx_;
  wy_.assign(static_cast<std::size_t>(max_side + detail::kGaussPad), 0.0F);
  capture_sum_.assign(static_cast<std::size_t>(cal_.width) * static_cast<std::size_t>(cal_.height),
                      0);
  state_.assign(cal_.elements.size(), ElementState{});
  readings_.assign(cal_.elements.size(), ElementReading{});
  for (std::size_t i = 0; i < readings_.size(); ++i)
    readings_[i].id = cal_.elements[i].id;
}

bool Extractor::geometry_matches(const ImageView& f) const {
  if (f.data == nullptr || f.width <= 0 || f.height <= 0 ||
      f.stride_bytes < static_cast<std::size_t>(f.width) * bytes_per_pixel(f.format)) {
    return false;
  }
  if (f.origin_x == 0 && f.origin_y == 0 && f.width == cal_.width && f.height == cal_.height)
    return true;
  if (!opt_.accept_regions) return false;
  // A region of interest: inside the sensor, holding every disk pixel.
  const std::int64_t x0 = f.origin_x;
  const std::int64_t y0 = f.origin_y;
  const std::int64_t x1 = x0 + f.width;
  const std::int64_t y1 = y0 + f.height;
  return x0 >= 0 && y0 >= 0 && x1 <= cal_.width && y1 <= cal_.height && x0 <= disks_.x &&
         y0 <= disks_.y && x1 >= disks_.x + disks_.width && y1 >= disks_.y + disks_.height;
}

// --- reference ----------------------------------------------------------------------------------

void Extractor::begin_reference() {
  std::fill(capture_sum_.begin(), capture_sum_.end(), 0U);
  capture_frames_ = 0;
}

ReferenceResult Extractor::refuse(ReferenceStatus s, std::uint32_t id, double value) {
  ReferenceResult r{s, capture_frames_, id, value};
  begin_reference();
  return r;
}

ReferenceResult Extractor::add_reference_frame(const ImageView& f) {
  if (!geometry_matches(f)) return refuse(ReferenceStatus::kWrongSize, 0, 0);
  if (bit_depth(f.format) != cal_.bit_depth) return refuse(ReferenceStatus::kWrongFormat, 0, 0);

  const auto w = static_cast<std::size_t>(cal_.width);
  if (capture_frames_ > 0) {
    // Motion check: no element may change by a contact's worth against the running mean.
    const auto n = static_cast<std::uint64_t>(capture_frames_);
    for (std::size_t i = 0; i < layout_.size(); ++i) {
      const ElementLayout& el = layout_[i];
      std::int64_t up = 0;
      std::int64_t down = 0;
      for (std::uint32_t s = el.span_begin; s < el.span_end; ++s) {
        const Span& sp = spans_[s];
        for (int x = sp.x0; x < sp.x1; ++x) {
          const std::uint64_t sum = capture_sum_[static_cast<std::size_t>(sp.y) * w + x];
          const auto mean_q = static_cast<std::int64_t>((sum * 256U + n / 2) / n);
          const std::int64_t d =
              static_cast<std::int64_t>(q8(f.at(x - f.origin_x, sp.y - f.origin_y))) - mean_q;
          up += std::max<std::int64_t>(d - floor_q_, 0);
          down += std::max<std::int64_t>(-d - floor_q_, 0);
        }
      }
      const double change = static_cast<double>(std::max(up, down)) / kQ;
      if (change >= cal_.contact_on) {
        return refuse(ReferenceStatus::kRefusedMotion, cal_.elements[i].id, change);
      }
    }
  }
  // The frame's pixels (the whole sensor, or the region of interest it covers).
  for (int y = 0; y < f.height; ++y) {
    std::uint32_t* sum = capture_sum_.data() + static_cast<std::size_t>(y + f.origin_y) * w +
                         static_cast<std::size_t>(f.origin_x);
    if (f.format == PixelFormat::kMono8) {
      const auto* row = f.row<std::uint8_t>(y);
      for (int x = 0; x < f.width; ++x)
        sum[x] += row[x];
    } else {
      const auto* row = f.row<std::uint16_t>(y);
      for (int x = 0; x < f.width; ++x)
        sum[x] += row[x];
    }
  }
  ++capture_frames_;
  if (capture_frames_ >= opt_.reference_frames) return complete_reference();
  return {ReferenceStatus::kCollecting, capture_frames_, 0, 0};
}

ReferenceResult Extractor::finish_reference() {
  return complete_reference();
}

ReferenceResult Extractor::complete_reference() {
  if (capture_frames_ == 0) return refuse(ReferenceStatus::kNoFrames, 0, 0);
  const auto n = static_cast<std::uint64_t>(capture_frames_);
  const auto w = static_cast<std::size_t>(cal_.width);
  std::vector<std::int32_t> mean_q(ref_q_.size());
  for (const Span& sp : spans_) {
    for (int x = sp.x0; x < sp.x1; ++x) {
      const std::uint64_t sum = capture_sum_[static_cast<std::size_t>(sp.y) * w + x];
      mean_q[sp.ref_offset + static_cast<std::uint32_t>(x - sp.x0)] =
          static_cast<std::int32_t>((sum * 256U + n / 2) / n);
    }
  }

  for (std::size_t i = 0; i < layout_.size(); ++i) {
    const ElementLayout& el = layout_[i];
    const ElementCalibration& ec = cal_.elements[i];
    if (has_reference_) {
      std::int64_t load = 0;
      for (std::uint32_t s = el.span_begin; s < el.span_end; ++s) {
        const Span& sp = spans_[s];
        for (std::uint32_t k = sp.ref_offset;
             k < sp.ref_offset + static_cast<std::uint32_t>(sp.x1 - sp.x0); ++k) {
          load += std::max<std::int64_t>(
              static_cast<std::int64_t>(mean_q[k]) - ref_q_[k] - floor_q_, 0);
        }
      }
      const double g = static_cast<double>(load) / kQ;
      if (g >= cal_.contact_on) return refuse(ReferenceStatus::kRefusedLoad, ec.id, g);
    }
    // Spot check: the inner disk may not stand above the rim ring by a contact's worth. A smooth
    // (vignetted) background has no such excess; a pressed element does. Tiny disks are skipped.
    if (opt_.reference_spot_check && ec.radius_px >= 3.0) {
      const double r_inner = 0.6 * ec.radius_px;
      const double r_rim = 0.8 * ec.radius_px;
      std::int64_t rim_sum = 0;
      std::int64_t rim_n = 0;
      std::int64_t inner_sum = 0;
      std::int64_t inner_n = 0;
      for (std::uint32_t s = el.span_begin; s < el.span_end; ++s) {
        const Span& sp = spans_[s];
        for (int x = sp.x0; x < sp.x1; ++x) {
          const double r = std::hypot(x - ec.center_px.x, sp.y - ec.center_px.y);
          const std::int32_t v = mean_q[sp.ref_offset + static_cast<std::uint32_t>(x - sp.x0)];
          if (r <= r_inner) {
            inner_sum += v;
            ++inner_n;
          } else if (r >= r_rim) {
            rim_sum += v;
            ++rim_n;
          }
        }
      }
      if (inner_n > 0 && rim_n > 0) {
        const double rim_mean = static_cast<double>(rim_sum) / static_cast<double>(rim_n);
        const double excess =
            (static_cast<double>(inner_sum) - rim_mean * static_cast<double>(inner_n)) / kQ;
        if (excess >= cal_.contact_on) return refuse(ReferenceStatus::kRefusedSpot, ec.id, excess);
      }
    }
  }

  ref_q_ = std::move(mean_q);
  build_block_tables();
  const PixelFormat fmt = cal_.bit_depth == 8 ? PixelFormat::kMono8 : PixelFormat::kMono16;
  reference_image_ = Image(cal_.width, cal_.height, fmt);
  for (int y = 0; y < cal_.height; ++y) {
    for (int x = 0; x < cal_.width; ++x) {
      const std::uint64_t sum = capture_sum_[static_cast<std::size_t>(y) * w + x];
      reference_image_.set(x, y, static_cast<std::uint32_t>((sum + n / 2) / n));
    }
  }
  has_reference_ = true;
  const int frames = capture_frames_;
  begin_reference();
  std::fill(state_.begin(), state_.end(), ElementState{});
  forget_previous();
  return {ReferenceStatus::kComplete, frames, 0, 0};
}

void Extractor::build_block_tables() {
  // No pixel passes this threshold: 256 * 65535 < it.
  constexpr std::int32_t kNever = (65535 << kQBits) + 1;
  const std::size_t n =
      blocks_.empty() ? 0
                      : blocks_.back().offset + static_cast<std::size_t>(blocks_.back().width) *
                                                    static_cast<std::size_t>(blocks_.back().height);
  BlockTables& t = tables_;
  t.thr.assign(n, kNever);
  t.ref.assign(n, detail::kOutsideDisk);
  t.thr_lo.assign(n, 0);
  if (cal_.bit_depth == 8) {
    t.thr_hi8.assign(n, 255);
    t.thr16.assign(n, 65535);
    t.ref16.assign(n, 65535);
    t.ref_hi8.assign(n, 255);
    t.ref_lo.assign(n, 0);
  } else {
    t.thr_hi16.assign(n, 65535);
  }
  for (std::size_t i = 0; i < layout_.size(); ++i) {
    const ElementLayout& el = layout_[i];
    const detail::Block& b = blocks_[i];
    for (std::uint32_t s = el.span_begin; s < el.span_end; ++s) {
      const Span& sp = spans_[s];
      for (int x = sp.x0; x < sp.x1; ++x) {
        const std::size_t at =
            b.offset + static_cast<std::size_t>(sp.y - b.y0) * static_cast<std::size_t>(b.width) +
            static_cast<std::size_t>(x - b.x0);
        set_block_pixel(at, ref_q_[sp.ref_offset + static_cast<std::size_t>(x - sp.x0)]);
      }
    }
  }
}

void Extractor::set_block_pixel(std::size_t at, std::int32_t ref_q) {
  const std::int64_t max_level = cal_.bit_depth == 8 ? 255 : 65535;
  const std::int32_t thr_q = ref_q + floor_q_;
  const std::int64_t t = thr_q;
  BlockTables& tb = tables_;
  tb.thr[at] = thr_q;
  tb.ref[at] = ref_q;
  // t >> 8 beyond the largest level: no pixel passes, and hi = max_level says the same.
  const std::int64_t hi = std::min<std::int64_t>(t >> kQBits, max_level);
  tb.thr_lo[at] = static_cast<std::uint8_t>(t & 0xFF);
  if (cal_.bit_depth == 8) {
    tb.thr_hi8[at] = static_cast<std::uint8_t>(hi);
    tb.thr16[at] = static_cast<std::uint16_t>(std::min<std::int64_t>(t, 65535));
    tb.ref16[at] = static_cast<std::uint16_t>(std::min<std::int32_t>(ref_q, 65535));
    tb.ref_hi8[at] = static_cast<std::uint8_t>(std::min(ref_q >> kQBits, 255));
    tb.ref_lo[at] = static_cast<std::uint8_t>(ref_q & 0xFF);
  } else {
    tb.thr_hi16[at] = static_cast<std::uint16_t>(hi);
  }
}

detail::BlockData Extractor::block_data() const noexcept {
  detail::BlockData d;
  d.thr = tables_.thr.data();
  d.ref = tables_.ref.data();
  d.thr16 = tables_.thr16.data();
  d.ref16 = tables_.ref16.data();
  d.thr_hi8 = tables_.thr_hi8.data();
  d.thr_lo = tables_.thr_lo.data();
  d.thr_hi16 = tables_.thr_hi16.data();
  d.ref_hi8 = tables_.ref_hi8.data();
  d.ref_lo = tables_.ref_lo.data();
  return d;
}

// --- per frame ----------------------------------------------------------------------------------

void Extractor::forget_previous() noexcept {
  has_previous_ = false;
}

namespace {

detail::FrameRef frame_ref(const ImageView& f) {
  return {f.data, f.stride_bytes, f.origin_x, f.origin_y};
}

}  // namespace

template <typename Pixel>
bool Extractor::windowed_pass(std::size_t element, const ImageView& f, double& x, double& y,
                              double half) const noexcept {
  const ElementLayout& el = layout_[element];
  const detail::Block& b = blocks_[element];
  const double reach = half + 0.5;
  const int col_lo = static_cast<int>(std::ceil(x - reach));
  const int col_hi = static_cast<int>(std::floor(x + reach));
  double s0 = 0;
  double sx = 0;
  double sy = 0;
  for (std::uint32_t s = el.span_begin; s < el.span_end; ++s) {
    const Span& sp = spans_[s];
    const double fy = soft_edge(half, sp.y - y);
    if (fy <= 0) continue;
    const int xa = std::max(sp.x0, col_lo);
    const int xb = std::min(sp.x1, col_hi + 1);
    const Pixel* row = f.row<Pixel>(sp.y - f.origin_y);
    // The G threshold of the row's block pixels, from column b.x0 on.
    const std::int32_t* thr =
        tables_.thr.data() + b.offset +
        static_cast<std::size_t>(sp.y - b.y0) * static_cast<std::size_t>(b.width);
    double r0 = 0;
    double rx = 0;
    for (int px = xa; px < xb; ++px) {
      const std::int32_t w = std::max(q8(row[px - f.origin_x]) - thr[px - b.x0], 0);
      if (w == 0) continue;
      const double wf = w * soft_edge(half, px - x);
      r0 += wf;
      rx += wf * (px - x);
    }
    s0 += fy * r0;
    sx += fy * rx;
    sy += fy * r0 * (sp.y - y);
  }
  if (!(s0 > 0)) return false;
  const double nx = x + sx / s0;
  const double ny = y + sy / s0;
  if (!std::isfinite(nx) || !std::isfinite(ny)) return false;
  x = nx;
  y = ny;
  return true;
}

template <typename Pixel>
bool Extractor::gaussian_pass(std::size_t element, const ImageView& f, double& x, double& y,
                              Vec2& sigma, bool per_axis) noexcept {
  const detail::Block& b = blocks_[element];
  const double sx = sigma.x;
  const double sy = sigma.y;
  // Beyond 12 sigmas the weights are below 1e-31: capping the reach there keeps every exponent
  // of the weights within exp_nonpositive's range (-a u^2 >= -72).
  const double reach = std::min(opt_.gaussian_reach_sigmas, 12.0);
  // x, y lie inside the disk and reach is at most 1024 * gaussian_reach_sigmas / 2: the
  // integer conversions are safe for any sane reach; clamp it anyway.
  const double rx = std::min(reach * sx, 1.0e6);
  const double ry = std::min(reach * sy, 1.0e6);
  const int row_lo = std::max(b.y0, ceil_int(y - ry));
  const int row_hi = std::min(b.y0 + b.height - 1, floor_int(y + ry));
  const int col_lo = std::max(b.x0, ceil_int(x - rx));
  const int col_hi = std::min(b.x0 + b.width - 1, floor_int(x + rx));
  if (row_hi < row_lo || col_hi < col_lo) return false;
  // The window lies in the disk when its farthest corner does (with a margin for rounding: the
  // disk's own test is exact).
  const ElementCalibration& ec = cal_.elements[element];
  const double far_x = std::max(ec.center_px.x - col_lo, col_hi - ec.center_px.x);
  const double far_y = std::max(ec.center_px.y - row_lo, row_hi - ec.center_px.y);
  const bool inside = far_x * far_x + far_y * far_y <= ec.radius_px * ec.radius_px * (1 - 1e-9);
  const detail::GaussWindow win{row_lo,
                                row_hi,
                                col_lo,
                                col_hi,
                                x,
                                y,
                                1.0 / (2.0 * sx * sx),
                                1.0 / (2.0 * sy * sy),
                                wx_.data() + detail::kGaussPad,
                                wxu_.data() + detail::kGaussPad,
                                wxu2_.data() + detail::kGaussPad,
                                wy_.data(),
                                inside};
  const detail::GaussSums g = sizeof(Pixel) == 1
                                  ? kernels_->gauss_u8(b, frame_ref(f), block_data(), win)
                                  : kernels_->gauss_u16(b, frame_ref(f), block_data(), win);
  if (!(g.s0 > 0)) return false;
  // Newton step on the score sum d (x - c) W(x - c) = 0; where the score is not concave
  // (a spot much wider than the weight) fall back to the weighted-centroid step.
  const double inv_sx2 = 1.0 / (sx * sx);
  const double inv_sy2 = 1.0 / (sy * sy);
  const double dfx = g.s2x * inv_sx2 - g.s0;
  const double dfy = g.s2y * inv_sy2 - g.s0;
  double step_x = dfx < 0 ? -g.s1x / dfx : g.s1x / g.s0;
  double step_y = dfy < 0 ? -g.s1y / dfy : g.s1y / g.s0;
  if (!(std::abs(step_x) <= sx) || !(std::abs(step_y) <= sy)) {
    step_x = g.s1x / g.s0;
    step_y = g.s1y / g.s0;
  }
  x += step_x;
  y += step_y;
  // The weighted second moment is the spot's variance combined with the weight's:
  // 1/m2 = 1/sigma_spot^2 + 1/sigma_weight^2 for a Gaussian spot. Per axis, or (a round weight)
  // the mean of the two.
  if (per_axis) {
    const double m2x = g.s2x / g.s0;
    const double m2y = g.s2y / g.s0;
    if (m2x > 0 && m2x < 0.95 * sx * sx) sigma.x = 1.0 / std::sqrt(1.0 / m2x - inv_sx2);
    if (m2y > 0 && m2y < 0.95 * sy * sy) sigma.y = 1.0 / std::sqrt(1.0 / m2y - inv_sy2);
  } else {
    const double m2 = (g.s2x + g.s2y) / (2.0 * g.s0);
    if (m2 > 0 && m2 < 0.95 * sx * sx) sigma.x = sigma.y = 1.0 / std::sqrt(1.0 / m2 - inv_sx2);
  }
  return std::isfinite(x) && std::isfinite(y);
}

namespace {

// The weights of the first centroid, the one every estimator starts from.
detail::MomentKind start_moments(CentroidEstimator e) noexcept {
  switch (e) {
    case CentroidEstimator::kPlain:
      return detail::MomentKind::kPlain;
    case CentroidEstimator::kThresholded:
      return detail::MomentKind::kThresholded;
    case CentroidEstimator::kWindowed:
      return detail::MomentKind::kThresholdedCount;
    case CentroidEstimator::kGaussian:
    case CentroidEstimator::kGaussianAxes:
      return detail::MomentKind::kStart;
  }
  return detail::MomentKind::kThresholded;
}

}  // namespace

template <typename Pixel>
void Extractor::gaussian_refine(std::size_t element, const ImageView& f, const detail::Moments& m,
                                double g, bool per_axis, Vec2& p) noexcept {
  const ElementCalibration& ec = cal_.elements[element];
  // Width of the weight from the spot: for a Gaussian of peak A above a floor f,
  // G = 2 pi sigma^2 (A - f - f ln(A / f)). The peak increment is the largest excess over
  // the threshold (whole gray levels) plus the floor. For an elliptical spot this is the
  // geometric mean of its two widths; per_axis then finds each axis's own from the first pass.
  const double fl = cal_.noise_floor;
  const double peak = m.peak > 0 ? m.peak + fl : 0.0;
  const double shape = fl > 0 ? peak - fl - fl * std::log(std::max(peak / fl, 1.0)) : peak;
  const double widest = std::max(0.6, ec.radius_px / 2);
  const double s0 =
      std::clamp(shape > 0.05 * peak && shape > 0 ? std::sqrt(g / (2 * std::numbers::pi * shape))
                                                  : ec.radius_px / 4,
                 0.6, widest);
  Vec2 sigma{s0, s0};
  double gx = p.x;
  double gy = p.y;
  if (!gaussian_pass<Pixel>(element, f, gx, gy, sigma, per_axis)) return;
  // A weight far from the spot's width loses efficiency: once more with the better width. Per
  // axis the widths of an elliptical spot part from the round start by less (aspect 1.5: about
  // a fifth each way), so there the bar is lower.
  const double bar = per_axis ? kAxesRepassChange : 0.25;
  if (std::abs(sigma.x - s0) > bar * s0 || std::abs(sigma.y - s0) > bar * s0) {
    sigma = {std::clamp(sigma.x, 0.6, widest), std::clamp(sigma.y, 0.6, widest)};
    double hx = p.x;
    double hy = p.y;
    if (gaussian_pass<Pixel>(element, f, hx, hy, sigma, per_axis)) {
      gx = hx;
      gy = hy;
    }
  }
  // Keep the estimate only inside the disk; the thresholded centroid always is.
  const double dx = gx - ec.center_px.x;
  const double dy = gy - ec.center_px.y;
  if (dx * dx + dy * dy <= ec.radius_px * ec.radius_px) p = {gx, gy};
}

template <typename Pixel>
Vec2 Extractor::centroid(std::size_t element, const ImageView& f, const detail::Moments& m,
                         double g) noexcept {
  const detail::Block& blk = blocks_[element];
  Vec2 p{blk.x0 + static_cast<double>(m.cx) / static_cast<double>(m.c0),
         blk.y0 + static_cast<double>(m.cy) / static_cast<double>(m.c0)};
  switch (opt_.estimator) {
    case CentroidEstimator::kPlain:
    case CentroidEstimator::kThresholded:
      break;
    case CentroidEstimator::kWindowed: {
      const double half =
          std::sqrt(static_cast<double>(m.above) / std::numbers::pi) + opt_.window_margin_px;
      windowed_pass<Pixel>(element, f, p.x, p.y, half);
      break;
    }
    case CentroidEstimator::kGaussian:
      gaussian_refine<Pixel>(element, f, m, g, false, p);
      break;
    case CentroidEstimator::kGaussianAxes:
      gaussian_refine<Pixel>(element, f, m, g, true, p);
      break;
  }
  return p;
}

inline void Extractor::record_contact(std::size_t element, Vec2 p, double g,
                                      std::uint32_t gap) noexcept {
  const double mm = cal_.mm_per_px;
  const ElementCalibration& ec = cal_.elements[element];
  ElementState& st = state_[element];
  ElementReading& r = readings_[element];
  r.x_px = p.x;
  r.y_px = p.y;
  r.ux_mm = (p.x - ec.zero_px.x) * mm;
  r.uy_mm = (p.y - ec.zero_px.y) * mm;
  r.fz = cal_.normal_curve(g);
  r.fx = cal_.shear_curve.odd(r.ux_mm);
  r.fy = cal_.shear_curve.odd(r.uy_mm);
  if (st.contact && gap > 0) {
    r.has_displacement = true;
    r.dx_mm = (p.x - st.x_px) * mm / gap;
    r.dy_mm = (p.y - st.y_px) * mm / gap;
  }
  st.contact = true;
  st.x_px = p.x;
  st.y_px = p.y;
}

template <typename Pixel>
void Extractor::measure_all(const ImageView& f, std::uint32_t gap) noexcept {
  const detail::FrameRef fr = frame_ref(f);
  const detail::BlockData data = block_data();
  const detail::MomentKind kind = start_moments(opt_.estimator);
  for (std::size_t i = 0; i < layout_.size(); ++i) {
    ElementState& st = state_[i];
    ElementReading& r = readings_[i];
    const detail::Block& blk = blocks_[i];

    r = ElementReading{};
    r.id = cal_.elements[i].id;
    // An element out of contact first gets its exact G on narrow integers, about the cost of
    // reading its pixels; only if that reaches contact.on does it get the full pass.
    if (!st.contact) {
      const detail::GSum gs = sizeof(Pixel) == 1 ? kernels_->exact_g_u8(blk, fr, data)
                                                 : kernels_->exact_g_u16(blk, fr, data);
      const double g = static_cast<double>(gs.g_q8()) / kQ;
      if (!(g >= cal_.contact_on)) {
        r.G = g;
        st = ElementState{};
        continue;
      }
    }
    const detail::Moments m = sizeof(Pixel) == 1 ? kernels_->moments_u8(blk, fr, data, kind)
                                                 : kernels_->moments_u16(blk, fr, data, kind);
    // The next element's rows start loading while this one is worked on (about a tenth of the
    // time at 41 contacts when frames come from the shared cache).
    if (i + 1 < layout_.size()) detail::prefetch_block<Pixel>(blocks_[i + 1], fr);
    const double g = static_cast<double>(m.g) / kQ;
    const bool contact = (st.contact ? g >= cal_.contact_off : g >= cal_.contact_on) && m.c0 > 0;

    r.G = g;
    r.contact = contact;
    if (!contact) {
      st = ElementState{};
      continue;
    }
    record_contact(i, centroid<Pixel>(i, f, m, g), g, gap);
  }
}

MeasureStatus Extractor::measure(const ImageView& f, FrameInfo info) noexcept {
  if (!has_reference_) return MeasureStatus::kNoReference;
  if (!geometry_matches(f)) return MeasureStatus::kWrongSize;
  if (bit_depth(f.format) != cal_.bit_depth) return MeasureStatus::kWrongFormat;

  std::uint32_t gap = 0;
  if (has_previous_ && info.sequence > previous_sequence_ &&
      info.sequence - previous_sequence_ <= opt_.max_gap_frames) {
    gap = static_cast<std::uint32_t>(info.sequence - previous_sequence_);
  }
  if (f.format == PixelFormat::kMono8) {
    measure_all<std::uint8_t>(f, gap);
  } else {
    measure_all<std::uint16_t>(f, gap);
  }
  has_previous_ = true;
  previous_sequence_ = info.sequence;
  return MeasureStatus::kOk;
}

}  // namespace tactile
