#include "tactile/control/slip_detector.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

#include "tactile/detail/multiversion.hpp"

#ifdef TACTILE_AVX2
#include <immintrin.h>
#endif

namespace tactile::control {

namespace {

// The compiled-in model of the learned detector (slip_train writes it).
#include "slip_model.inc"

static_assert(kSlipModel.features == kSlipFeatures,
              "slip_model.inc was trained on another feature set: run slip_train again");
static_assert(kSlipModel.depth >= 1 && kSlipModel.depth <= 8, "slip_train fits depths 1 to 8");

bool usable(const ElementReading& r) {
  return r.contact && std::isfinite(r.fz) && std::isfinite(r.dx_mm) && std::isfinite(r.dy_mm) &&
         std::isfinite(r.x_px) && std::isfinite(r.y_px) && std::isfinite(r.fx) &&
         std::isfinite(r.fy);
}

// |(x, y)| without hypot's care for overflow and rounding (hypot costs most of the field
// detector's time); a result that overflows is infinite, and every output is checked finite.
inline double length(double x, double y) {
  return std::sqrt(x * x + y * y);
}

// A learned detector's signal: in float, 0 where it is not finite.
inline float finite_signal(double v) {
  const auto x = static_cast<float>(v);
  return std::isfinite(x) ? x : 0.0f;
}

// The learned detector's signals (kSlipFeatureNames' indices) that are each element's own, and
// those that are the fingertip's, the same for every element of a frame (written once per frame):
// each signal in exactly one of them, in the order decide_field computes them.
constexpr std::array<std::size_t, 16> kElementSignals{0, 1,  2,  3,  4,  5,  6,  7,
                                                      8, 10, 17, 18, 22, 23, 24, 25};
constexpr std::array<std::size_t, 14> kFingertipSignals{9,  11, 12, 13, 14, 15, 16,
                                                        19, 20, 21, 26, 27, 28, 29};

constexpr bool each_signal_once() {
  std::array<int, kSlipFeatures> seen{};
  for (std::size_t k : kElementSignals)
    ++seen[k];
  for (std::size_t k : kFingertipSignals)
    ++seen[k];
  for (int times : seen)
    if (times != 1) return false;
  return kElementSignals[10] == kSlipFeatureReasons;
}
static_assert(each_signal_once(), "every signal is the element's or the fingertip's, once");

std::size_t element_count(const FingertipInput& in) {
  return std::min(in.elements.size(), kMaxSlipElements);
}

// The rigid motion of the contact over the frame: d(p) = t + w * perp(p - c), with p in pixels,
// d in mm (w in mm per pixel). Weighted least squares over the elements with weight 1.
struct RigidFit {
  double cx = 0, cy = 0;  // centroid of the fitted elements, px
  double tx = 0, ty = 0;  // translation, mm per frame
  double w = 0;           // rotation, mm per px per frame
  std::uint32_t n = 0;

  double at_x(double y) const { return tx - w * (y - cy); }
  double at_y(double x) const { return ty + w * (x - cx); }
};

template <typename Use>
RigidFit fit_rigid(const FingertipInput& in, std::size_t count, Use use) {
  RigidFit fit;
  double sx = 0, sy = 0, sdx = 0, sdy = 0;
  for (std::size_t i = 0; i < count; ++i) {
    if (!use(i)) continue;
    const ElementReading& r = in.elements[i];
    sx += r.x_px;
    sy += r.y_px;
    sdx += r.dx_mm;
    sdy += r.dy_mm;
    ++fit.n;
  }
  if (fit.n == 0) return fit;
  const double n = fit.n;
  fit.cx = sx / n;
  fit.cy = sy / n;
  fit.tx = sdx / n;
  fit.ty = sdy / n;
  if (fit.n < 3) return fit;
  double num = 0, den = 0;
  for (std::size_t i = 0; i < count; ++i) {
    if (!use(i)) continue;
    const ElementReading& r = in.elements[i];
    const double px = r.x_px - fit.cx;
    const double py = r.y_px - fit.cy;
    num += px * (r.dy_mm - fit.ty) - py * (r.dx_mm - fit.tx);
    den += px * px + py * py;
  }
  if (den > 1e-9 && std::isfinite(num / den)) fit.w = num / den;
  return fit;
}

// The compiled-in model over `n` elements' signals by column, tree by tree: each split compares
// one column with one threshold; each element's leaves are summed in model_score's order, in
// float: the same scores, so the same decisions.
void score_portable(const SlipColumns& columns, std::size_t n, float* score) noexcept {
  std::array<std::uint32_t, kMaxSlipElements> leaf{};
  for (std::size_t e = 0; e < n; ++e)
    score[e] = static_cast<float>(kSlipModel.base);
  for (std::size_t t = 0; t < kSlipModel.trees; ++t) {
    for (std::size_t e = 0; e < n; ++e)
      leaf[e] = 0;
    for (std::size_t d = 0; d < kSlipModel.depth; ++d) {
      const std::size_t split = t * kSlipModel.depth + d;
      const float* column = columns[kSlipModelFeature[split]].data();
      const float threshold = kSlipModelThreshold[split];
      for (std::size_t e = 0; e < n; ++e)
        leaf[e] |= static_cast<std::uint32_t>(column[e] > threshold) << d;
    }
    const float* leaves = &kSlipModelLeaf[t << kSlipModel.depth];
    for (std::size_t e = 0; e < n; ++e)
      score[e] += leaves[leaf[e]];
  }
}

#ifdef TACTILE_AVX2

constexpr std::size_t kSplits = kSlipModel.trees * kSlipModel.depth;
// Trees whose leaf indices the AVX2 scoring holds at once (4 KB).
constexpr std::size_t kTreeChunk = 64;

// The model's thresholds by signal, at compile time: each signal's distinct thresholds in
// ascending order, and each split's rank among its signal's. With an element's count of a
// signal's thresholds below its value, `value > threshold` of the split is `count > rank`, exactly
// (the thresholds below a value are the first `count`; NaN is below none, as for `>`).
struct ThresholdRanks {
  std::array<std::size_t, kSlipFeatures + 1> begin{};  // signal k's: [begin[k], begin[k + 1])
  std::array<float, kSplits> ascending{};
  std::array<std::int8_t, kSplits> rank{};  // of each split, minus 128 (compared signed)
  std::size_t most = 0;                     // thresholds of the signal that has the most
};

constexpr ThresholdRanks rank_thresholds() {
  ThresholdRanks r;
  std::size_t size = 0;
  for (std::size_t k = 0; k < kSlipFeatures; ++k) {
    r.begin[k] = size;
    for (std::size_t s = 0; s < kSplits; ++s) {
      if (kSlipModelFeature[s] != k) continue;
      const float v = kSlipModelThreshold[s];
      std::size_t i = r.begin[k];
      while (i < size && r.ascending[i] < v)
        ++i;
      if (i < size && r.ascending[i] == v) continue;
      for (std::size_t j = size; j > i; --j)
        r.ascending[j] = r.ascending[j - 1];
      r.ascending[i] = v;
      ++size;
    }
    r.most = std::max(r.most, size - r.begin[k]);
  }
  r.begin[kSlipFeatures] = size;
  for (std::size_t s = 0; s < kSplits; ++s) {
    const std::size_t k = kSlipModelFeature[s];
    std::size_t i = r.begin[k];
    while (r.ascending[i] != kSlipModelThreshold[s])
      ++i;
    r.rank[s] = static_cast<std::int8_t>(static_cast<int>(i - r.begin[k]) - 128);
  }
  return r;
}

inline constexpr ThresholdRanks kRanks = rank_thresholds();
static_assert(kRanks.most <= 255, "a signal's count of thresholds must fit in a byte");

// Pass 1 for `Q` blocks of 8 elements from `first` (a multiple of 32): each signal's count of
// thresholds below each element's value, minus 128, in signed bytes (the blocks past Q count 0).
template <std::size_t Q>
TACTILE_AVX2 void count_thresholds_avx2(
    const SlipColumns& columns, std::size_t first,
    std::int8_t (&count)[kSlipFeatures][kMaxSlipElements]) noexcept {
  for (std::size_t k = 0; k < kSlipFeatures; ++k) {
    if (kRanks.begin[k] == kRanks.begin[k + 1]) continue;  // no split on it
    const float* column = columns[k].data() + first;
    __m256i c[4];
    for (auto& v : c)
      v = _mm256_set1_epi32(-128);
    for (std::size_t j = kRanks.begin[k]; j < kRanks.begin[k + 1]; ++j) {
      const __m256 threshold = _mm256_set1_ps(kRanks.ascending[j]);
      for (std::size_t q = 0; q < Q; ++q) {
        const __m256 above = _mm256_cmp_ps(_mm256_loadu_ps(column + 8 * q), threshold, _CMP_GT_OQ);
        c[q] = _mm256_sub_epi32(c[q], _mm256_castps_si256(above));
      }
    }
    // The packs interleave 128-bit lanes; the permutation undoes it.
    const __m256i bytes =
        _mm256_packs_epi16(_mm256_packs_epi32(c[0], c[1]), _mm256_packs_epi32(c[2], c[3]));
    _mm256_store_si256(
        reinterpret_cast<__m256i*>(count[k] + first),
        _mm256_permutevar8x32_epi32(bytes, _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7)));
  }
}

// Pass 3 for `B` blocks of 8 elements from block `b`: trees [first, first + trees) of the chunk
// whose leaf indices `leaf` holds, added to `score` tree by tree. The blocks' sums are independent
// chains, so the gathers of one tree overlap.
template <std::size_t B>
TACTILE_AVX2 void sum_leaves_avx2(const std::uint8_t (&leaf)[kTreeChunk][kMaxSlipElements],
                                  std::size_t first, std::size_t trees, std::size_t b,
                                  float* score) noexcept {
  __m256 sum[B];
  for (std::size_t q = 0; q < B; ++q)
    sum[q] = _mm256_loadu_ps(score + 8 * (b + q));
  for (std::size_t t = 0; t < trees; ++t) {
    const float* leaves = &kSlipModelLeaf[(first + t) << kSlipModel.depth];
    for (std::size_t q = 0; q < B; ++q) {
      const __m256i index = _mm256_cvtepu8_epi32(
          _mm_loadl_epi64(reinterpret_cast<const __m128i*>(leaf[t] + 8 * (b + q))));
      sum[q] = _mm256_add_ps(sum[q], _mm256_i32gather_ps(leaves, index, 4));
    }
  }
  for (std::size_t q = 0; q < B; ++q)
    _mm256_storeu_ps(score + 8 * (b + q), sum[q]);
}

// The same scores in AVX2, compiled by function attribute only (the build has no -mavx2) and used
// only where the processor has it. Three passes over the frame's elements, 32 at a time in bytes
// where they can be:
//   1. each signal's count of thresholds below each element's value (8 floats per comparison);
//   2. each tree's leaf index from the counts (32 elements per comparison);
//   3. each element's leaves summed tree by tree, as model_score (8 elements per gather).
TACTILE_AVX2 void score_avx2(const SlipColumns& columns, std::size_t n, float* score) noexcept {
  static_assert(kMaxSlipElements % 32 == 0);
  constexpr std::size_t kDepth = kSlipModel.depth;
  const std::size_t halves = (n + 31) / 32;  // of 32 elements; the columns hold 64
  alignas(32) std::int8_t count[kSlipFeatures][kMaxSlipElements];
  for (std::size_t h = 0; h < halves; ++h) {
    switch (std::min<std::size_t>((n - 32 * h + 7) / 8, 4)) {
      case 1:
        count_thresholds_avx2<1>(columns, 32 * h, count);
        break;
      case 2:
        count_thresholds_avx2<2>(columns, 32 * h, count);
        break;
      case 3:
        count_thresholds_avx2<3>(columns, 32 * h, count);
        break;
      default:
        count_thresholds_avx2<4>(columns, 32 * h, count);
        break;
    }
  }
  // Passes 2 and 3 by chunks of trees.
  alignas(32) std::uint8_t leaf[kTreeChunk][kMaxSlipElements];
  const std::size_t blocks = (n + 7) / 8;
  for (std::size_t b = 0; b < blocks; ++b)
    _mm256_storeu_ps(score + 8 * b, _mm256_set1_ps(static_cast<float>(kSlipModel.base)));
  for (std::size_t first = 0; first < kSlipModel.trees; first += kTreeChunk) {
    const std::size_t trees = std::min(kTreeChunk, kSlipModel.trees - first);
    for (std::size_t t = 0; t < trees; ++t) {
      for (std::size_t h = 0; h < halves; ++h) {
        // Bit d of the index is split d's answer: from the last split to the first, the index
        // doubles and the answer (all ones, -1, when true) is subtracted.
        __m256i index = _mm256_setzero_si256();
        for (std::size_t d = kDepth; d-- > 0;) {
          const std::size_t split = (first + t) * kDepth + d;
          const __m256i c = _mm256_load_si256(
              reinterpret_cast<const __m256i*>(count[kSlipModelFeature[split]] + 32 * h));
          const __m256i above = _mm256_cmpgt_epi8(c, _mm256_set1_epi8(kRanks.rank[split]));
          index = _mm256_sub_epi8(_mm256_add_epi8(index, index), above);
        }
        _mm256_store_si256(reinterpret_cast<__m256i*>(leaf[t] + 32 * h), index);
      }
    }
    std::size_t b = 0;
    for (; b + 4 <= blocks; b += 4)
      sum_leaves_avx2<4>(leaf, first, trees, b, score);
    switch (blocks - b) {
      case 3:
        sum_leaves_avx2<3>(leaf, first, trees, b, score);
        break;
      case 2:
        sum_leaves_avx2<2>(leaf, first, trees, b, score);
        break;
      case 1:
        sum_leaves_avx2<1>(leaf, first, trees, b, score);
        break;
      default:
        break;
    }
  }
}
#endif

using ScoreFn = void (*)(const SlipColumns&, std::size_t, float*) noexcept;

ScoreFn vector_scoring() noexcept {
#ifdef TACTILE_AVX2
  if (tactile::detail::cpu_has_avx2_fma()) return score_avx2;
#endif
  return nullptr;
}

// Chosen once, at start-up.
const ScoreFn kVectorScoring = vector_scoring();

}  // namespace

const std::array<const char*, kSlipFeatures> kSlipFeatureNames{"moved_dr",
                                                               "departed_dr",
                                                               "surface_dr",
                                                               "load",
                                                               "load_prev",
                                                               "fz_n",
                                                               "dfz_n",
                                                               "moved_prev_dr",
                                                               "departed_prev_dr",
                                                               "rigid_dr",
                                                               "rotation_dr",
                                                               "arm_speed_mmps",
                                                               "arm_yaw_dps",
                                                               "share_moved",
                                                               "share_departed",
                                                               "total_fz_n",
                                                               "total_dfz_rel",
                                                               "field_reasons",
                                                               "field_was",
                                                               "measured",
                                                               "dr_um",
                                                               "mu",
                                                               "ft_n",
                                                               "align",
                                                               "moved_prev2_dr",
                                                               "dfz_prev_n",
                                                               "arm_dr",
                                                               "fps",
                                                               "share_slipping",
                                                               "share_slipping_prev"};

// Summed in float, tree by tree, as the detector's batch evaluation: the same decisions.
double SlipDetector::model_score(const SlipFeatures& x) noexcept {
  auto score = static_cast<float>(kSlipModel.base);
  for (std::size_t t = 0; t < kSlipModel.trees; ++t) {
    std::size_t leaf = 0;
    for (std::size_t d = 0; d < kSlipModel.depth; ++d) {
      const std::size_t split = t * kSlipModel.depth + d;
      leaf |= static_cast<std::size_t>(x[kSlipModelFeature[split]] > kSlipModelThreshold[split])
              << d;
    }
    score += kSlipModelLeaf[(t << kSlipModel.depth) + leaf];
  }
  return static_cast<double>(score);
}

SlipFeatures SlipDetector::features(std::size_t fingertip, std::size_t element) const noexcept {
  SlipFeatures x{};
  if (!has_features_[fingertip][element]) return x;
  const std::size_t e = column_of_[fingertip][element];
  for (std::size_t k = 0; k < kSlipFeatures; ++k)
    x[k] = columns_[fingertip][k][e];
  return x;
}

void SlipDetector::model_scores(const SlipColumns& columns, std::size_t n,
                                std::array<float, kMaxSlipElements>& score,
                                ModelScoring scoring) noexcept {
  n = std::min(n, kMaxSlipElements);
  if (scoring == ModelScoring::kVector && kVectorScoring != nullptr) {
    kVectorScoring(columns, n, score.data());
  } else {
    score_portable(columns, n, score.data());
  }
}

const char* SlipDetector::model_scoring() noexcept {
  return kVectorScoring != nullptr ? "avx2" : "portable";
}

double SlipDetector::model_decision() noexcept {
  return static_cast<double>(static_cast<float>(kSlipModel.decision));
}

std::size_t SlipDetector::model_trees() noexcept {
  return kSlipModel.trees;
}

const char* to_string(ElementSlipState s) {
  switch (s) {
    case ElementSlipState::kNone:
      return "none";
    case ElementSlipState::kStick:
      return "stick";
    case ElementSlipState::kIncipient:
      return "incipient";
    case ElementSlipState::kSlip:
      return "slip";
  }
  return "?";
}

ArmMotion ArmMotionEstimator::update(const WristPose& wrist, double now_s) noexcept {
  const bool finite =
      is_finite(wrist.position_m) && std::isfinite(wrist.yaw_rad) && std::isfinite(now_s);
  if (!finite) return motion_ = ArmMotion{};
  if (has_last_ && now_s > last_s_) {
    const double dt = now_s - last_s_;
    const double speed = norm(wrist.position_m - last_.position_m) / dt;
    const double yaw = (wrist.yaw_rad - last_.yaw_rad) / dt;
    motion_ = ArmMotion{std::isfinite(speed) ? speed : 0.0, std::isfinite(yaw) ? yaw : 0.0};
  } else if (!has_last_) {
    motion_ = ArmMotion{};
  }
  if (!has_last_ || now_s > last_s_) {
    last_ = wrist;
    last_s_ = now_s;
    has_last_ = true;
  }
  return motion_;
}

bool paper_slip(const ElementReading& r, double threshold_mm) noexcept {
  if (!r.contact || !r.has_displacement) return false;
  if (!std::isfinite(r.fz) || !std::isfinite(r.dx_mm) || !std::isfinite(r.dy_mm)) return false;
  const double moved = std::hypot(r.dx_mm, r.dy_mm);
  return std::isfinite(moved) && moved > threshold_mm;
}

SlipDetector::SlipDetector(SlipDetectorKind kind, const Config& cfg)
    : kind_(kind),
      rho_(cfg.field_partial_slip_ratio),
      edge_(cfg.field_edge_ratio),
      drop_(cfg.field_drop_ratio),
      mu_initial_(cfg.field_mu_initial),
      fn_min_n_(cfg.field_min_fz_n),
      arm_speed_mps_(cfg.field_arm_speed_mps),
      arm_yaw_rps_(cfg.field_arm_yaw_rate_rps) {
  reset();
}

void SlipDetector::reset() noexcept {
  for (auto& tip : history_)
    tip.fill(History{});
  mu_.fill(mu_initial_);
  out_.fill(FingertipSlip{});
  total_fz_.fill(0.0);
  last_ts_ns_.fill(0);
  period_s_.fill(0.0);
  share_slipping_.fill(0.0);
  for (auto& tip : has_features_)
    tip.fill(false);
}

const FingertipSlip& SlipDetector::update(std::size_t f, const FingertipInput& in,
                                          double threshold_mm, const ArmMotion& arm) noexcept {
  FingertipSlip& out = out_[f];
  out = FingertipSlip{};
  if (kind_ != SlipDetectorKind::kPaper) out.mu_estimate = mu_[f];
  if (!in.fresh) return out;
  if (kind_ == SlipDetectorKind::kPaper) {
    decide_paper(in, threshold_mm, out);
  } else {
    decide_field(f, in, threshold_mm, arm, out);
  }
  for (std::size_t i = 0; i < element_count(in); ++i) {
    const ElementSlipState s = out.state[i];
    if (s == ElementSlipState::kIncipient) ++out.incipient;
    if (slipping(s)) ++out.slipping;
    if (static_cast<int>(s) > static_cast<int>(out.fingertip)) out.fingertip = s;
  }
  return out;
}

void SlipDetector::decide_paper(const FingertipInput& in, double threshold_mm,
                                FingertipSlip& out) noexcept {
  for (std::size_t i = 0; i < element_count(in); ++i) {
    const ElementReading& r = in.elements[i];
    if (!r.contact || !r.has_displacement) continue;
    if (paper_slip(r, threshold_mm)) {
      out.state[i] = ElementSlipState::kSlip;
      out.slip_mm[i] = std::hypot(r.dx_mm, r.dy_mm);
      out.reasons[i] = kSlipMoved;
    } else {
      out.state[i] = ElementSlipState::kStick;
    }
  }
}

void SlipDetector::decide_field(std::size_t f, const FingertipInput& in, double thr,
                                const ArmMotion& arm, FingertipSlip& out) noexcept {
  const std::size_t count = element_count(in);
  auto& hist = history_[f];
  double& mu = mu_[f];
  for (std::size_t i = count; i < kMaxSlipElements; ++i)
    hist[i] = History{};

  // (a) The rigid motion of the contact: fitted to every element with a displacement, then
  // again without the elements that departed from the first fit by more than dr.
  const auto measured = [&](std::size_t i) {
    const ElementReading& r = in.elements[i];
    return usable(r) && r.has_displacement;
  };
  RigidFit fit = fit_rigid(in, count, measured);
  if (fit.n >= 3) {
    const RigidFit first = fit;
    const auto inlier = [&](std::size_t i) {
      if (!measured(i)) return false;
      const ElementReading& r = in.elements[i];
      return length(r.dx_mm - first.at_x(r.y_px), r.dy_mm - first.at_y(r.x_px)) <= thr;
    };
    const RigidFit second = fit_rigid(in, count, inlier);
    if (second.n >= 3) fit = second;
  }
  out.rigid_mm = std::isfinite(length(fit.tx, fit.ty)) ? length(fit.tx, fit.ty) : 0.0;
  const bool contact_moves = out.rigid_mm > thr;
  const bool arm_moves =
      std::abs(arm.speed_mps) > arm_speed_mps_ || std::abs(arm.yaw_rate_rps) > arm_yaw_rps_;

  // (b) The friction estimate: no element's load ratio exceeds mu. A ratio counts once it held
  // for two frames in a row (the smaller of the two), so one noisy frame does not set it.
  for (std::size_t i = 0; i < count; ++i) {
    const ElementReading& r = in.elements[i];
    const History& h = hist[i];
    if (!usable(r) || r.fz < fn_min_n_ || !h.valid) continue;
    const double ratio = std::min(length(r.fx, r.fy) / r.fz, h.ratio);
    if (std::isfinite(ratio) && ratio > mu && ratio < 10.0) mu = ratio;
  }
  out.mu_estimate = mu;

  // The fingertip's signals for the learned detector: how much of the contact moved or left the
  // fit, and how its total normal force changed (a grip that opens or closes).
  const bool learn = kind_ == SlipDetectorKind::kLearned;
  SlipColumns& columns = columns_[f];
  auto& has_feats = has_features_[f];
  auto& column_of = column_of_[f];
  has_feats.fill(false);
  std::size_t n = 0;  // elements with signals: columns [0, n)
  std::uint32_t n_measured = 0, n_moved = 0, n_departed = 0;
  double total_fz = 0;
  if (learn) {
    for (std::size_t i = 0; i < count; ++i) {
      const ElementReading& r = in.elements[i];
      if (!usable(r)) continue;
      total_fz += r.fz;
      if (!r.has_displacement) continue;
      ++n_measured;
      // Squared lengths against thr^2: a count, cheaper than hypot.
      const double thr2 = thr * thr;
      if (r.dx_mm * r.dx_mm + r.dy_mm * r.dy_mm > thr2) ++n_moved;
      if (fit.n >= 3) {
        const double ex = r.dx_mm - fit.at_x(r.y_px), ey = r.dy_mm - fit.at_y(r.x_px);
        if (ex * ex + ey * ey > thr2) ++n_departed;
      }
    }
  }
  const double last_total_fz = total_fz_[f];
  if (learn) total_fz_[f] = total_fz;
  // The frame period from the camera's timestamps (0 until two frames came 0-1 s apart): the
  // arm's motion over one frame, in dr, against what the elements show.
  const std::int64_t ts = in.camera_timestamp_ns;
  if (ts > last_ts_ns_[f] && ts - last_ts_ns_[f] < 1'000'000'000 && last_ts_ns_[f] > 0)
    period_s_[f] = static_cast<double>(ts - last_ts_ns_[f]) * 1e-9;
  last_ts_ns_[f] = ts;
  const double period = period_s_[f];
  std::uint32_t n_field_slipping = 0;
  const double inv = thr > 0 ? 1.0 / thr : 0.0;  // lengths in units of thr

  for (std::size_t i = 0; i < count; ++i) {
    const ElementReading& r = in.elements[i];
    History& h = hist[i];
    if (!usable(r)) {
      h = History{};
      continue;
    }
    const double ft = length(r.fx, r.fy);
    const double ratio = r.fz >= fn_min_n_ ? ft / r.fz : 0.0;
    if (!r.has_displacement) {
      h = History{};
      h.valid = true;
      h.ratio = ratio;
      h.fz = r.fz;
      out.state[i] = ElementSlipState::kNone;
      continue;
    }
    const double moved = length(r.dx_mm, r.dy_mm);
    const double departed =
        fit.n >= 3 ? length(r.dx_mm - fit.at_x(r.y_px), r.dy_mm - fit.at_y(r.x_px)) : 0.0;
    const double surface = fit.n >= 3 ? length(fit.at_x(r.y_px), fit.at_y(r.x_px)) : moved;
    const bool loaded = ratio >= rho_ * mu;
    const bool at_edge = ratio >= edge_ * mu;
    const bool was = h.valid && h.sliding;
    // A breakaway: the load ratio fell from the cone's edge by more than drop * mu (a grip that
    // opens lowers F_t and F_n together: not a breakaway).
    const bool broke =
        h.valid && h.ratio >= edge_ * mu && r.fz >= fn_min_n_ && h.ratio - ratio > drop_ * mu;
    const bool moved_loaded = moved > thr && (loaded || was);
    // Only an element at the cone's edge (now or in the last frame) can leave a contact's rigid
    // motion: a release, or the slipping rim of a partial slip. Elsewhere a departure is the
    // fit's error (an opening grip, a contact of few elements).
    const bool left_rigid = departed > thr && (at_edge || h.ratio >= edge_ * mu || was);
    // (c) Still slipping: at the cone's edge while the contact or the arm moves.
    const bool dragged = was && at_edge && (contact_moves || surface > thr || arm_moves);
    const std::uint8_t why = (moved_loaded ? kSlipMoved : 0) | (left_rigid ? kSlipLeftRigid : 0) |
                             (broke ? kSlipBrokeAway : 0) | (dragged ? kSlipDragged : 0);
    const bool slides = why != 0;
    if (learn) {
      // The element's own signals; the fingertip's (the same for every element) after the loop.
      const double rx = r.x_px - fit.cx, ry = r.y_px - fit.cy;
      const double rigid = out.rigid_mm;
      const double align =
          moved > 0 && rigid > 0 ? (r.dx_mm * fit.tx + r.dy_mm * fit.ty) / (moved * rigid) : 0.0;
      const double m = mu > 0 ? 1.0 / mu : 0.0;
      const double own[] = {
          moved * inv,                  // moved_dr
          departed * inv,               // departed_dr
          surface * inv,                // surface_dr
          ratio * m,                    // load
          h.valid ? h.ratio * m : 0.0,  // load_prev
          r.fz,                         // fz_n
          h.valid ? r.fz - h.fz : 0.0,  // dfz_n
          h.valid ? h.moved : 0.0,      // moved_prev_dr
          h.valid ? h.departed : 0.0,   // departed_prev_dr
          fit.n >= 3 ? std::abs(fit.w) * std::sqrt(rx * rx + ry * ry) * inv : 0.0,  // rotation_dr
          static_cast<double>(why),                                                 // field_reasons
          was ? 1.0 : 0.0,                                                          // field_was
          ft,                                                                       // ft_n
          align,                                                                    // align
          h.valid ? h.moved2 : 0.0,  // moved_prev2_dr
          h.valid ? h.dfz : 0.0,     // dfz_prev_n
      };
      static_assert(std::size(own) == kElementSignals.size());
      for (std::size_t j = 0; j < kElementSignals.size(); ++j)
        columns[kElementSignals[j]][n] = finite_signal(own[j]);
      column_of[i] = static_cast<std::uint8_t>(n++);
      has_feats[i] = true;
      if (why != 0) ++n_field_slipping;
    }
    out.reasons[i] = why;
    if (slides) {
      // Gross slip where the contact itself moves over the element (translation or rotation);
      // incipient where the element alone left a contact that sticks.
      out.state[i] =
          contact_moves || surface > thr ? ElementSlipState::kSlip : ElementSlipState::kIncipient;
      const double v = std::max({departed, surface, moved});
      out.slip_mm[i] = std::isfinite(v) ? v : 0.0;
    } else {
      out.state[i] = ElementSlipState::kStick;
    }
    h = History{true,
                why != 0,
                ratio,
                r.fz,
                h.valid ? r.fz - h.fz : 0.0,
                moved * inv,
                h.valid ? h.moved : 0.0,
                departed * inv};
  }
  if (!learn) return;

  // The learned detector: the fingertip's signals complete the columns (the share of the contact
  // the field detector decided slipping, now and in the last frame, among them); then the model
  // decides each element.
  const double share = n_measured > 0 ? static_cast<double>(n_field_slipping) / n_measured : 0.0;
  const double share_prev = share_slipping_[f];
  share_slipping_[f] = share;
  const double fingertip[] = {
      out.rigid_mm * inv,                                                   // rigid_dr
      arm.speed_mps * 1e3,                                                  // arm_speed_mmps
      arm.yaw_rate_rps * (180.0 / 3.14159265358979323846),                  // arm_yaw_dps
      n_measured > 0 ? static_cast<double>(n_moved) / n_measured : 0.0,     // share_moved
      n_measured > 0 ? static_cast<double>(n_departed) / n_measured : 0.0,  // share_departed
      total_fz,                                                             // total_fz_n
      (total_fz - last_total_fz) / std::max(last_total_fz, 0.01),           // total_dfz_rel
      static_cast<double>(n_measured),                                      // measured
      thr * 1e3,                                                            // dr_um
      mu,                                                                   // mu
      arm.speed_mps * 1e3 * period * inv,                                   // arm_dr
      period > 0 ? 1.0 / period : 0.0,                                      // fps
      share,                                                                // share_slipping
      share_prev,                                                           // share_slipping_prev
  };
  static_assert(std::size(fingertip) == kFingertipSignals.size());
  for (std::size_t j = 0; j < kFingertipSignals.size(); ++j)
    std::fill_n(columns[kFingertipSignals[j]].begin(), n, finite_signal(fingertip[j]));
  if (kSlipModel.trees == 0) return;
  model_scores(columns, n, score_);
  for (std::size_t i = 0; i < count; ++i) {
    if (!has_feats[i]) continue;
    const std::size_t e = column_of[i];
    const bool slides = score_[e] > static_cast<float>(kSlipModel.decision);
    const std::uint8_t why = out.reasons[i];
    out.reasons[i] = slides ? (why != 0 ? why : kSlipLearned) : 0;
    if (slides) {
      // Signals 0-2: moved, departed and the surface's motion, in dr.
      out.state[i] = contact_moves || columns[2][e] > 1.0f ? ElementSlipState::kSlip
                                                           : ElementSlipState::kIncipient;
      const double v =
          static_cast<double>(std::max({columns[0][e], columns[1][e], columns[2][e]})) * thr;
      out.slip_mm[i] = std::isfinite(v) ? v : 0.0;
    } else {
      out.state[i] = ElementSlipState::kStick;
      out.slip_mm[i] = 0.0;
    }
  }
}

}  // namespace tactile::control
