// The calibration curves from applied loads against measured values: a piecewise-linear curve
// through (0, 0), non-decreasing, knots at quantiles of the measured values, knot forces by
// non-negative least squares on the increments between knots (so the curve is monotone by
// construction), and the refusals of a fit that should not be used.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "calibrate.hpp"

namespace tactile::calibrate {
namespace {

// Solves the m x m system M s = v (row-major M) by Gaussian elimination with partial pivoting.
std::vector<double> solve(std::vector<double> m, std::vector<double> v) {
  const std::size_t n = v.size();
  for (std::size_t c = 0; c < n; ++c) {
    std::size_t p = c;
    for (std::size_t r = c + 1; r < n; ++r)
      if (std::abs(m[r * n + c]) > std::abs(m[p * n + c])) p = r;
    if (p != c) {
      for (std::size_t k = 0; k < n; ++k)
        std::swap(m[c * n + k], m[p * n + k]);
      std::swap(v[c], v[p]);
    }
    const double d = m[c * n + c];
    if (d == 0.0) continue;  // the ridge keeps this from happening
    for (std::size_t r = c + 1; r < n; ++r) {
      const double f = m[r * n + c] / d;
      if (f == 0.0) continue;
      for (std::size_t k = c; k < n; ++k)
        m[r * n + k] -= f * m[c * n + k];
      v[r] -= f * v[c];
    }
  }
  std::vector<double> s(n, 0.0);
  for (std::size_t c = n; c-- > 0;) {
    double acc = v[c];
    for (std::size_t k = c + 1; k < n; ++k)
      acc -= m[c * n + k] * s[k];
    s[c] = m[c * n + c] != 0.0 ? acc / m[c * n + c] : 0.0;
  }
  return s;
}

// One observation: an applied load against the measured value, signed (shear) or not.
struct Obs {
  std::uint32_t element = 0;
  int axis = 0;  // 0: normal or x, 1: y
  double applied = 0;
  double measured = 0;
};

struct Spec {
  const char* curve;          // "normal curve"
  const char* measured;       // "G", "u"
  const char* measured_unit;  // "", " mm"
  const char* knots_option;   // "--normal-knots"
  const char* rms_option;     // "--max-rms-normal"
  bool odd = false;           // the shear curve: f(-u) = -f(u)
};

const char* axis_name(const Spec& spec, int axis) {
  if (!spec.odd) return "";
  return axis == 0 ? " along x" : " along y";
}

std::string num(double v) {
  return fmt::format("{:.4g}", v);
}

// v rounded up to `digits` significant digits (positive v).
double round_up_significant(double v, int digits) {
  if (!(v > 0)) return v;
  const double p = std::pow(10.0, digits - 1 - static_cast<int>(std::floor(std::log10(v))));
  return std::ceil(v * p - 1e-9) / p;
}

// Refuses a direction (normal, shear x, shear y) the samples cannot show: the measured value
// does not rise with the applied load beyond its noise (over all elements together: a straight
// line's slope within 5 of its standard errors of 0, or the rise over the loads' range under 2
// noise sigmas of one sample). Says what to record instead: loads that move the measured value by
// 10 of its noise sigmas, from the curve the fit replaces, or else 10 times the largest load here.
void check_observable(const std::vector<Obs>& obs, const Spec& spec,
                      const CurveFitOptions& options) {
  for (int axis = 0; axis < (spec.odd ? 2 : 1); ++axis) {
    double n = 0;
    double sa = 0;
    double sm = 0;
    double lo = INFINITY;
    double hi = -INFINITY;
    for (const Obs& o : obs) {
      if (o.axis != axis) continue;
      n += 1;
      sa += o.applied;
      sm += o.measured;
      lo = std::min(lo, o.applied);
      hi = std::max(hi, o.applied);
    }
    if (n < 3) continue;
    const double ma = sa / n;
    const double mm = sm / n;
    double sxx = 0;
    double sxy = 0;
    for (const Obs& o : obs) {
      if (o.axis != axis) continue;
      sxx += (o.applied - ma) * (o.applied - ma);
      sxy += (o.applied - ma) * (o.measured - mm);
    }
    if (!(sxx > 0)) continue;  // one load level: refused with its own message
    const double slope = sxy / sxx;
    double sse = 0;
    for (const Obs& o : obs) {
      if (o.axis != axis) continue;
      const double r = o.measured - mm - slope * (o.applied - ma);
      sse += r * r;
    }
    const double noise = std::sqrt(sse / std::max(n - 2, 1.0));
    const double se = noise / std::sqrt(sxx);
    const double rise = slope * (hi - lo);
    // A clear fall is a flipped axis: check_monotone says so.
    if (std::abs(slope) >= 5 * se && std::abs(rise) >= 2 * noise) continue;
    const double largest = std::max(std::abs(lo), std::abs(hi));
    double need = 0;
    std::string how;
    if (options.present_curve && noise > 0) {
      need = (*options.present_curve)(10 * noise);
      how = fmt::format("the present {} gives that load for a {} of 10 noise sigmas", spec.curve,
                        spec.measured);
    }
    if (!(need > largest)) {
      need = 10 * largest;
      how = "10 times the largest load here";
    }
    const char* direction = !spec.odd ? "normal" : axis == 0 ? "shear x" : "shear y";
    const char* column = !spec.odd ? "fz_N" : axis == 0 ? "fx_N" : "fy_N";
    throw std::runtime_error(fmt::format(
        "{}: the {} direction cannot be seen in these samples: applied {} from {} to {} N moved "
        "the measured {}{} by {}{}, within its noise ({}{} per sample); record frames with {} "
        "loads of at least {} N{} ({}), at several levels up to the largest the sensor meets in "
        "use",
        spec.curve, direction, column, num(lo), num(hi), spec.measured, axis_name(spec, axis),
        num(rise), spec.measured_unit, num(noise), spec.measured_unit, direction,
        num(round_up_significant(need, 2)),
        spec.odd ? (axis == 0 ? " in x, both signs" : " in y, both signs") : "", how));
  }
}

// Refuses data whose mean measured value falls as the applied load rises, per element and axis
// and over all elements together.
void check_monotone(const std::vector<Obs>& obs, const Spec& spec, double tolerance) {
  // (element or UINT32_MAX for all, axis) -> applied level -> (sum, count)
  std::map<std::pair<std::uint64_t, int>, std::map<double, std::pair<double, std::size_t>>> groups;
  for (const Obs& o : obs) {
    for (const std::uint64_t key :
         {static_cast<std::uint64_t>(o.element), std::uint64_t{1} << 40}) {
      auto& level = groups[{key, o.axis}][o.applied];
      level.first += o.measured;
      level.second += 1;
    }
  }
  for (const auto& [key, levels] : groups) {
    if (levels.size() < 2) continue;
    double lo = INFINITY;
    double hi = -INFINITY;
    for (const auto& [applied, acc] : levels) {
      const double mean = acc.first / static_cast<double>(acc.second);
      lo = std::min(lo, mean);
      hi = std::max(hi, mean);
    }
    const double allowed = tolerance * (hi - lo);
    double best = -INFINITY;
    double best_applied = 0;
    for (const auto& [applied, acc] : levels) {
      const double mean = acc.first / static_cast<double>(acc.second);
      if (best - mean > allowed) {
        const std::string who = key.first == (std::uint64_t{1} << 40)
                                    ? std::string("all elements together")
                                    : "element " + std::to_string(key.first);
        throw std::runtime_error(fmt::format(
            "{}: the data are not monotone: for {}, the mean measured {}{} falls from {}{} at "
            "{} N to {}{} at {} N (more than {} % of its range; --monotone-tolerance){}",
            spec.curve, who, spec.measured, axis_name(spec, key.second), num(best),
            spec.measured_unit, num(best_applied), num(mean), spec.measured_unit, num(applied),
            num(100 * tolerance),
            spec.odd ? ": is an axis of the loads flipped against the image, or the camera "
                       "mirrored?"
                     : ": check the loads, the reference and the element ids"));
      }
      if (mean > best) {
        best = mean;
        best_applied = applied;
      }
    }
  }
}

double round_significant(double v, int digits) {
  if (v == 0.0) return 0.0;
  const double p = std::pow(10.0, digits - 1 - static_cast<int>(std::floor(std::log10(v))));
  return std::round(v * p) / p;
}

CurveFit fit(const std::vector<Obs>& obs, const Spec& spec, const CurveFitOptions& options) {
  if (options.knots < 1 || options.knots > 32)
    throw std::invalid_argument(
        fmt::format("{} must be 1..32, is {}", spec.knots_option, options.knots));
  if (!(options.monotone_tolerance >= 0))
    throw std::invalid_argument("--monotone-tolerance must not be negative");
  if (!(options.max_rms_n >= 0))
    throw std::invalid_argument(std::string(spec.rms_option) + " must not be negative");

  // The fit works on x >= 0: the shear curve's data are folded with its odd symmetry.
  struct Point {
    double x, y;
  };
  std::vector<Point> pts;
  std::vector<double> loaded_x;
  std::map<double, int> levels;
  double max_applied = 0;
  for (const Obs& o : obs) {
    const double sign = spec.odd && o.measured < 0 ? -1.0 : 1.0;
    pts.push_back({sign * o.measured, sign * o.applied});
    if (o.applied != 0) {
      loaded_x.push_back(sign * o.measured);
      levels[o.applied] += 1;
    }
    max_applied = std::max(max_applied, std::abs(o.applied));
  }
  const std::size_t k_count = static_cast<std::size_t>(options.knots);
  const std::size_t needed = std::max<std::size_t>(2 * k_count, 4);
  if (loaded_x.size() < needed) {
    throw std::runtime_error(fmt::format(
        "{}: too few points: {} samples with a load, at least {} are needed for {} knots ({})",
        spec.curve, loaded_x.size(), needed, options.knots, spec.knots_option));
  }
  if (levels.size() < 2) {
    throw std::runtime_error(
        fmt::format("{}: too few points: every sample has the same applied load ({} N); at least 2 "
                    "different loads are needed",
                    spec.curve, num(levels.begin()->first)));
  }
  check_observable(obs, spec, options);
  check_monotone(obs, spec, options.monotone_tolerance);

  std::sort(loaded_x.begin(), loaded_x.end());
  const double top = loaded_x.back();
  if (!(top > 0)) {
    throw std::runtime_error(fmt::format(
        "{}: every measured {} of a loaded sample is 0: nothing to fit (is the sensor seen, the "
        "reference right, the element in contact?)",
        spec.curve, spec.measured));
  }
  // Knots start at quantiles of the loaded samples' measured values, at least `gap` apart; the
  // last sits at the largest. Then each inner knot moves, one at a time, to the measured value
  // where the squared error is least (a free-knot least-squares fit): quantiles alone fall
  // between the clusters of data taken at a few load levels and would bend the curve where the
  // sensor does not. Candidates are measured values, not any x: between two clusters every knot
  // position fits the data about equally well, and a knot there bends the curve where nothing
  // was measured; a knot on a measured value keeps the curve straight between clusters.
  const double gap = top / (4.0 * static_cast<double>(k_count));
  std::vector<double> knots{0.0};
  for (std::size_t k = 1; k <= k_count; ++k) {
    const double q = static_cast<double>(k) / static_cast<double>(k_count);
    const double idx = q * static_cast<double>(loaded_x.size() - 1);
    const auto i = static_cast<std::size_t>(std::floor(idx));
    const double frac = idx - static_cast<double>(i);
    double x =
        i + 1 < loaded_x.size() ? loaded_x[i] * (1 - frac) + loaded_x[i + 1] * frac : loaded_x[i];
    if (k == k_count) x = std::max(top, knots.back() + gap);
    if (x - knots.back() >= gap) knots.push_back(x);
  }
  // Up to 256 measured values at even quantiles: the places a knot may move to.
  std::vector<double> candidates;
  {
    constexpr std::size_t kMaxCandidates = 256;
    const std::size_t n = loaded_x.size();
    const std::size_t count = std::min(n, kMaxCandidates);
    for (std::size_t c = 0; c < count; ++c) {
      const double v = loaded_x[count > 1 ? c * (n - 1) / (count - 1) : 0];
      if (v > 0 && (candidates.empty() || v > candidates.back())) candidates.push_back(v);
    }
  }
  // Basis: ramp j rises from 0 at knot j to 1 at knot j+1 and stays 1; the last keeps rising
  // (the curve's extrapolation). Its coefficient is the force added over segment j.
  const auto solve_for = [&pts](const std::vector<double>& kn, double* sse) {
    const std::size_t m = kn.size() - 1;
    std::vector<double> a;
    std::vector<double> b;
    a.reserve(pts.size() * m);
    for (const Point& p : pts) {
      for (std::size_t j = 0; j < m; ++j) {
        const double t = (p.x - kn[j]) / (kn[j + 1] - kn[j]);
        a.push_back(j + 1 == m ? std::max(t, 0.0) : std::clamp(t, 0.0, 1.0));
      }
      b.push_back(p.y);
    }
    std::vector<double> delta = nnls(a, m, b);
    if (sse != nullptr) {
      double s = 0;
      for (std::size_t r = 0; r < b.size(); ++r) {
        double v = -b[r];
        for (std::size_t j = 0; j < m; ++j)
          v += a[r * m + j] * delta[j];
        s += v * v;
      }
      *sse = s;
    }
    return delta;
  };
  double best_sse = 0;
  solve_for(knots, &best_sse);
  for (int sweep = 0; sweep < 6 && knots.size() > 2; ++sweep) {
    const double before = best_sse;
    for (std::size_t j = 1; j + 1 < knots.size(); ++j) {
      const double lo = knots[j - 1] + gap;
      const double hi = knots[j + 1] - gap;
      if (!(hi > lo)) continue;
      const auto try_at = [&](double x) {
        std::vector<double> trial = knots;
        trial[j] = x;
        double e = 0;
        solve_for(trial, &e);
        if (e < best_sse) {
          best_sse = e;
          knots[j] = x;
        }
      };
      for (const double x : candidates)
        if (x >= lo && x <= hi) try_at(x);
    }
    if (before - best_sse <= 1e-12 * std::max(before, 1e-300)) break;
  }
  for (std::size_t j = 1; j < knots.size(); ++j)
    knots[j] = std::max(round_significant(knots[j], 4), std::nextafter(knots[j - 1], INFINITY));
  const std::vector<double> delta = solve_for(knots, nullptr);
  std::vector<double> ys{0.0};
  double acc = 0;
  for (double d : delta) {
    acc += d;
    ys.push_back(std::round(acc * 1e6) / 1e6);
  }
  CurveFit out;
  out.curve = PiecewiseLinear(knots, ys);
  out.max_rms_n = options.max_rms_n > 0 ? options.max_rms_n : 0.05 * max_applied;

  std::map<std::uint32_t, std::pair<double, ElementError>> per;
  double all_sq = 0;
  for (const Obs& o : obs) {
    const double predicted = spec.odd ? out.curve.odd(o.measured) : out.curve(o.measured);
    const double err = std::abs(o.applied - predicted);
    auto& [sq, e] = per[o.element];
    e.element = o.element;
    e.n += 1;
    sq += err * err;
    e.max_n = std::max(e.max_n, err);
    out.all.n += 1;
    all_sq += err * err;
    out.all.max_n = std::max(out.all.max_n, err);
  }
  out.all.rms_n = std::sqrt(all_sq / static_cast<double>(std::max<std::size_t>(out.all.n, 1)));
  for (auto& [id, entry] : per) {
    entry.second.rms_n = std::sqrt(entry.first / static_cast<double>(entry.second.n));
    out.per_element.push_back(entry.second);
  }
  const ElementError* worst = nullptr;
  for (const ElementError& e : out.per_element)
    if (worst == nullptr || e.rms_n > worst->rms_n) worst = &e;
  if (worst != nullptr && worst->rms_n > out.max_rms_n) {
    out.problem = fmt::format(
        "{}: the fit error is too large: element {} has RMS {} N (max {} N over {} samples), "
        "above {} {} N{}; check that element and its loads, or allow more with {}",
        spec.curve, worst->element, num(worst->rms_n), num(worst->max_n), worst->n,
        options.max_rms_n > 0 ? spec.rms_option : "the default limit (5 % of the largest load)",
        num(out.max_rms_n),
        out.all.rms_n > out.max_rms_n ? fmt::format(" (all elements: RMS {} N)", num(out.all.rms_n))
                                      : std::string(),
        spec.rms_option);
  }
  return out;
}

}  // namespace

std::vector<double> nnls(const std::vector<double>& a, std::size_t cols,
                         const std::vector<double>& b) {
  const std::size_t n = b.size();
  if (cols == 0 || a.size() != n * cols) throw std::invalid_argument("nnls: A and b do not match");
  std::vector<double> ata(cols * cols, 0.0);
  std::vector<double> atb(cols, 0.0);
  for (std::size_t r = 0; r < n; ++r) {
    const double* row = a.data() + r * cols;
    for (std::size_t i = 0; i < cols; ++i) {
      atb[i] += row[i] * b[r];
      for (std::size_t j = 0; j < cols; ++j)
        ata[i * cols + j] += row[i] * row[j];
    }
  }
  double diag = 0;
  for (std::size_t i = 0; i < cols; ++i)
    diag = std::max(diag, ata[i * cols + i]);
  const double ridge = 1e-12 * std::max(diag, 1.0);
  double scale = 0;
  for (double v : atb)
    scale = std::max(scale, std::abs(v));
  const double tol = 1e-12 * std::max(scale, 1e-300);

  std::vector<double> x(cols, 0.0);
  std::vector<bool> passive(cols, false);
  const auto gradient = [&](std::size_t i) {
    double g = atb[i];
    for (std::size_t j = 0; j < cols; ++j)
      g -= ata[i * cols + j] * x[j];
    return g;
  };
  const auto solve_passive = [&]() {
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < cols; ++i)
      if (passive[i]) idx.push_back(i);
    const std::size_t p = idx.size();
    std::vector<double> m(p * p);
    std::vector<double> v(p);
    for (std::size_t i = 0; i < p; ++i) {
      v[i] = atb[idx[i]];
      for (std::size_t j = 0; j < p; ++j)
        m[i * p + j] = ata[idx[i] * cols + idx[j]] + (i == j ? ridge : 0.0);
    }
    const std::vector<double> s = solve(m, v);
    std::vector<double> full(cols, 0.0);
    for (std::size_t i = 0; i < p; ++i)
      full[idx[i]] = s[i];
    return full;
  };
  for (std::size_t outer = 0; outer < 3 * cols + 10; ++outer) {
    std::size_t best = cols;
    double best_g = tol;
    for (std::size_t i = 0; i < cols; ++i) {
      if (passive[i]) continue;
      const double g = gradient(i);
      if (g > best_g) {
        best_g = g;
        best = i;
      }
    }
    if (best == cols) break;
    passive[best] = true;
    for (std::size_t inner = 0; inner < 3 * cols + 10; ++inner) {
      const std::vector<double> s = solve_passive();
      bool feasible = true;
      double alpha = 1.0;
      for (std::size_t i = 0; i < cols; ++i) {
        if (passive[i] && s[i] <= 0) {
          feasible = false;
          alpha = std::min(alpha, x[i] / (x[i] - s[i]));
        }
      }
      if (feasible) {
        x = s;
        break;
      }
      for (std::size_t i = 0; i < cols; ++i) {
        x[i] += alpha * (s[i] - x[i]);
        if (passive[i] && x[i] <= 1e-15 * std::max(1.0, std::abs(s[i]))) {
          passive[i] = false;
          x[i] = 0;
        }
      }
    }
  }
  for (double& v : x)
    v = std::max(v, 0.0);
  return x;
}

CurveFit fit_normal_curve(const std::vector<Sample>& samples, const CurveFitOptions& options) {
  std::vector<Obs> obs;
  for (const Sample& s : samples)
    obs.push_back({s.element, 0, s.fz_n, s.G});
  if (obs.empty()) throw std::runtime_error("normal curve: no samples");
  return fit(obs, {"normal curve", "G", "", "--normal-knots", "--max-rms-normal", false}, options);
}

CurveFit fit_shear_curve(const std::vector<Sample>& samples, const CurveFitOptions& options) {
  std::vector<Obs> obs;
  for (const Sample& s : samples) {
    if (!s.contact) continue;
    if (s.has_x) obs.push_back({s.element, 0, s.fx_n, s.ux_mm});
    if (s.has_y) obs.push_back({s.element, 1, s.fy_n, s.uy_mm});
  }
  if (obs.empty()) {
    throw std::runtime_error(
        "shear curve: no samples in contact with fx_N/ux_mm or fy_N/uy_mm (use --normal-only to "
        "keep the calibration's shear curve)");
  }
  return fit(obs, {"shear curve", "u", " mm", "--shear-knots", "--max-rms-shear", true}, options);
}

}  // namespace tactile::calibrate
