#include "harness.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <numbers>
#include <utility>

#include "baselines.hpp"
#include "tactile/util/percentile.hpp"

namespace tactile::bench {
namespace {

constexpr int kReferenceFrames = 16;
constexpr int kReferenceEvery = 40;  // frames measured per reference capture

using testing::SpotShape;

testing::SceneOptions scene_options(const SpotSetting& s) {
  testing::SceneOptions o;
  o.bit_depth = s.depth;
  o.noise_sigma = s.noise_sigma();
  // Shot noise as large as the read noise at the background: gain = background / sigma^2.
  o.shot_noise_gain = s.shot_noise ? o.background / (o.noise_sigma * o.noise_sigma) : 0;
  return o;
}

// The spot's extent: its largest sigma plus a plateau.
double spot_extent(const SpotSetting& s) {
  // The feeler cluster (load 40 px^2) reaches about 6 px: 3.5 x 2.5 + 1.5 px holds it.
  if (s.shape == SpotShape::kFeelers) return 2.5;
  const double sy = s.shape == SpotShape::kElliptical ? s.aspect * s.sigma : s.sigma;
  return std::max(s.sigma, sy) + (s.shape == SpotShape::kFlatTop ? s.flat_radius : 0.0);
}

// A disk that holds the spot out to 3.5 sigma wherever it sits (up to 1 px off centre).
double disk_radius(const SpotSetting& s) {
  return std::max(12.0, std::ceil(3.5 * spot_extent(s) + 1.5));
}

// G of a disk of n pixels that holds only noise of sigma `noise` under a floor of k sigma, as
// a mean and a standard deviation: per pixel the excess max(e - k sigma, 0) has mean
// sigma (phi(k) - k Q(k)) and second moment sigma^2 ((1 + k^2) Q(k) - k phi(k)).
std::pair<double, double> noise_g(double n, double noise, double k) {
  const double phi = std::exp(-k * k / 2) / std::sqrt(2 * std::numbers::pi);
  const double q = 0.5 * std::erfc(k / std::sqrt(2.0));
  const double mean = noise * (phi - k * q);
  const double second = noise * noise * ((1 + k * k) * q - k * phi);
  return {n * mean, std::sqrt(n * std::max(second - mean * mean, 0.0))};
}

// A grid of up to 8 x 5 elements, spaced so that neighbouring spots stay apart. contact.on
// sits 10 standard deviations above the G that noise alone gives a disk (the reference capture
// compares frames with it too), so that faint spots still count as contacts.
Calibration accuracy_calibration(const testing::SceneOptions& o, double radius,
                                 double floor_sigmas) {
  const double spacing = 2 * radius + 10;
  const int cols = std::clamp(static_cast<int>((o.width - 8) / spacing), 1, 8);
  const int rows = std::clamp(static_cast<int>((o.height - 8) / spacing), 1, 5);
  Calibration cal = testing::grid_calibration(o, cols, rows, spacing, radius);
  const double scale = testing::level_scale(o.bit_depth);
  cal.noise_floor = floor_sigmas * o.noise_sigma * scale;
  // Noise of a frame against another (the capture's motion check), shot noise included.
  double noise = o.noise_sigma * std::sqrt(2.0);
  if (o.shot_noise_gain > 0) noise = std::hypot(noise, std::sqrt(o.background / o.shot_noise_gain));
  const auto pixels = static_cast<double>(disk_pixel_count(cal.elements[0].center_px, radius));
  const auto [mean, sd] = noise_g(pixels, noise, cal.noise_floor / scale / noise);
  cal.contact_on = std::max(20.0, std::ceil(mean + 10 * sd)) * scale;
  cal.contact_off = 0.6 * cal.contact_on;
  validate(cal);
  return cal;
}

testing::Spot make_spot(const SpotSetting& s, Vec2 at) {
  testing::Spot spot;
  spot.center = at;
  spot.peak = s.peak();
  spot.sigma = s.sigma;
  spot.shape = s.shape;
  spot.sigma_y = s.shape == SpotShape::kElliptical ? s.aspect * s.sigma : 0;
  spot.flat_radius = s.flat_radius;
  return spot;
}

// Everything that measures one frame: the core extractors (one per method), the OpenCV
// baseline; the floor computes no centroid and is skipped.
struct Measurers {
  struct Core {
    const Method* method;
    std::unique_ptr<Extractor> ex;
  };
  std::vector<Core> cores;
  const Method* opencv_method = nullptr;
  std::unique_ptr<OpenCvBaseline> opencv;
  std::vector<Calibration> cals;  // one per distinct floor, kept alive for the baselines

  Measurers(const std::vector<Method>& methods, const testing::SceneOptions& o,
            const std::function<Calibration(double)>& make_cal) {
    cals.reserve(methods.size());
    for (const Method& m : methods) {
      if (m.kind == Method::Kind::kFloor) continue;
      cals.push_back(make_cal(m.floor_sigmas));
      if (m.kind == Method::Kind::kCore) {
        ExtractorOptions opt = options_for(m);
        opt.reference_frames = kReferenceFrames;
        opt.reference_spot_check = false;
        cores.push_back({&m, std::make_unique<Extractor>(cals.back(), opt)});
      } else {
        opencv_method = &m;
        opencv = std::make_unique<OpenCvBaseline>(cals.back());
      }
    }
    (void)o;
  }

  // True when every extractor took the frames as its new reference.
  bool reference(const std::vector<Image>& frames) {
    bool all = true;
    for (Core& c : cores) {
      c.ex->begin_reference();
      ReferenceResult r;
      for (const Image& f : frames)
        r = c.ex->add_reference_frame(f.view());
      all = all && r.status == ReferenceStatus::kComplete;
    }
    if (opencv) opencv->set_reference(frames);
    return all;
  }
};

std::size_t method_count(const std::vector<Method>& methods) {
  std::size_t n = 0;
  for (const Method& m : methods)
    if (m.kind != Method::Kind::kFloor) ++n;
  return n;
}

}  // namespace

double SpotSetting::peak() const {
  return pnr <= 100 ? 2.0 * pnr : 200.0;
}

double SpotSetting::noise_sigma() const {
  return peak() / pnr;
}

std::string SpotSetting::shape_name() const {
  switch (shape) {
    case SpotShape::kGaussian:
      return "gaussian";
    case SpotShape::kElliptical: {
      // The issue-2 grid's aspect 1.5 keeps its old name.
      if (aspect == 1.5) return "elliptical";
      char name[32];
      std::snprintf(name, sizeof name, "elliptical-a%g", aspect);
      return name;
    }
    case SpotShape::kFlatTop:
      return "flat-top";
    case SpotShape::kFeelers:
      return "feelers";
  }
  return "?";
}

Bound cramer_rao(const SpotSetting& s, double radius, int reference_frames) {
  const testing::SceneOptions o = scene_options(s);
  const double scale = testing::level_scale(s.depth);
  // Everything in the image's gray levels.
  const double read_var = o.noise_sigma * o.noise_sigma * scale * scale;
  const double quant_var = 1.0 / 12.0;
  const double n_ref = reference_frames;
  util::Random rng(99);
  double inv_fx = 0;
  double inv_fy = 0;
  constexpr int kPhases = 16;
  constexpr double kH = 1e-4;
  for (int i = 0; i < kPhases; ++i) {
    const Vec2 c{100 + rng.uniform(-0.5, 0.5), 100 + rng.uniform(-0.5, 0.5)};
    const Vec2 disk{100, 100};
    const testing::Spot spot = make_spot(s, c);
    double fx = 0;
    double fy = 0;
    for (const DiskRow& r : disk_rows(disk, radius)) {
      for (int x = r.x0; x < r.x1; ++x) {
        const double bg = o.background * scale;
        const double mu = bg + testing::spot_at(spot, x, r.y) * scale;
        // Variance of the increment: the frame's noise plus the reference mean's.
        double var = (read_var + quant_var) * (1 + 1 / n_ref);
        if (s.shot_noise) var += (mu + bg / n_ref) * scale / o.shot_noise_gain;
        testing::Spot sx = spot;
        sx.center.x += kH;
        testing::Spot sx2 = spot;
        sx2.center.x -= kH;
        testing::Spot sy = spot;
        sy.center.y += kH;
        testing::Spot sy2 = spot;
        sy2.center.y -= kH;
        const double dx =
            (testing::spot_at(sx, x, r.y) - testing::spot_at(sx2, x, r.y)) * scale / (2 * kH);
        const double dy =
            (testing::spot_at(sy, x, r.y) - testing::spot_at(sy2, x, r.y)) * scale / (2 * kH);
        fx += dx * dx / var;
        fy += dy * dy / var;
      }
    }
    inv_fx += 1 / fx;
    inv_fy += 1 / fy;
  }
  return {std::sqrt(inv_fx / kPhases), std::sqrt(inv_fy / kPhases)};
}

double cramer_rao_simple(const SpotSetting& s) {
  return std::sqrt(2 / std::numbers::pi) * s.noise_sigma() / s.peak();
}

// --- ErrorStats ---------------------------------------------------------------------------------

void ErrorStats::add_axis(Axis& a, double e, double off, double pos) {
  const double f[4] = {1, off, std::sin(2 * std::numbers::pi * pos),
                       std::cos(2 * std::numbers::pi * pos)};
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j)
      a.xtx[i][j] += f[i] * f[j];
    a.xte[i] += f[i] * e;
  }
  a.ee += e * e;
}

void ErrorStats::add(double ex, double ey, double off_x, double off_y, double true_x,
                     double true_y) {
  add_axis(ax_, ex, off_x, true_x);
  add_axis(ay_, ey, off_y, true_y);
  ++n_;
}

double ErrorStats::rms_x() const {
  return n_ > 0 ? std::sqrt(ax_.ee / static_cast<double>(n_)) : 0;
}

double ErrorStats::rms_y() const {
  return n_ > 0 ? std::sqrt(ay_.ee / static_cast<double>(n_)) : 0;
}

// Least squares by Gauss-Jordan on the 4 x 4 normal equations; standard errors from the
// residual variance and the inverse's diagonal.
void ErrorStats::solve(const Axis& a, std::int64_t n, double coef[4], double se[4]) {
  double m[4][8];
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      m[i][j] = a.xtx[i][j];
      m[i][4 + j] = i == j ? 1 : 0;
    }
  }
  for (int c = 0; c < 4; ++c) {
    int p = c;
    for (int r = c + 1; r < 4; ++r)
      if (std::abs(m[r][c]) > std::abs(m[p][c])) p = r;
    for (int j = 0; j < 8; ++j)
      std::swap(m[c][j], m[p][j]);
    const double d = m[c][c];
    if (d == 0) {
      for (int i = 0; i < 4; ++i)
        coef[i] = se[i] = 0;
      return;
    }
    for (int j = 0; j < 8; ++j)
      m[c][j] /= d;
    for (int r = 0; r < 4; ++r) {
      if (r == c) continue;
      const double f = m[r][c];
      for (int j = 0; j < 8; ++j)
        m[r][j] -= f * m[c][j];
    }
  }
  double rss = a.ee;
  for (int i = 0; i < 4; ++i) {
    coef[i] = 0;
    for (int j = 0; j < 4; ++j)
      coef[i] += m[i][4 + j] * a.xte[j];
    rss -= coef[i] * a.xte[i];
  }
  const double var = std::max(rss, 0.0) / std::max<double>(1, static_cast<double>(n - 4));
  for (int i = 0; i < 4; ++i)
    se[i] = std::sqrt(std::max(0.0, var * m[i][4 + i]));
}

double ErrorStats::bias() const {
  double worst = 0;
  for (const Axis* a : {&ax_, &ay_}) {
    double c[4];
    double se[4];
    solve(*a, n_, c, se);
    worst = std::max({worst, std::abs(c[0]), std::abs(c[1]), std::hypot(c[2], c[3])});
  }
  return worst;
}

double ErrorStats::bias_se() const {
  double worst = 0;
  for (const Axis* a : {&ax_, &ay_}) {
    double c[4];
    double se[4];
    solve(*a, n_, c, se);
    worst = std::max({worst, se[0], se[1], std::max(se[2], se[3])});
  }
  return worst;
}

// --- accuracy -----------------------------------------------------------------------------------

std::vector<AccuracyRow> run_accuracy(const SpotSetting& s, const std::vector<Method>& methods,
                                      int frames, std::uint64_t seed) {
  const testing::SceneOptions o = scene_options(s);
  const double radius = disk_radius(s);
  const auto make_cal = [&](double floor_sigmas) {
    return accuracy_calibration(o, radius, floor_sigmas);
  };
  Measurers meas(methods, o, make_cal);
  const Calibration& cal = meas.cals.front();
  const testing::SceneRenderer renderer(o, &cal);
  util::Random rng(seed);
  std::vector<Image> reference(kReferenceFrames);
  Image frame;
  const std::size_t nm = method_count(methods);
  std::vector<ErrorStats> stats(nm);
  std::vector<testing::Spot> spots(cal.elements.size());
  for (int f = 0; f < frames; ++f) {
    if (f % kReferenceEvery == 0) {
      // A capture refused for noise that looks like motion is taken again.
      for (int attempt = 0; attempt < 5; ++attempt) {
        for (Image& r : reference)
          renderer.render({}, rng, r);
        if (meas.reference(reference)) break;
        std::fprintf(stderr, "  reference capture refused, again\n");
      }
    }
    for (std::size_t e = 0; e < cal.elements.size(); ++e) {
      const Vec2 c = cal.elements[e].center_px;
      spots[e] = make_spot(s, c + Vec2{rng.uniform(-1, 1), rng.uniform(-1, 1)});
    }
    renderer.render(spots, rng, frame);
    const auto score = [&](std::size_t k, std::size_t e, bool contact, double x, double y) {
      if (!contact) {
        stats[k].add_miss();
        return;
      }
      const Vec2 t = spots[e].center;
      const Vec2 c = cal.elements[e].center_px;
      stats[k].add(x - t.x, y - t.y, t.x - c.x, t.y - c.y, t.x, t.y);
    };
    std::size_t k = 0;
    for (auto& core : meas.cores) {
      core.ex->forget_previous();
      core.ex->measure(frame.view(), {static_cast<std::uint64_t>(f), 0});
      const auto rd = core.ex->readings();
      for (std::size_t e = 0; e < rd.size(); ++e)
        score(k, e, rd[e].contact, rd[e].x_px, rd[e].y_px);
      ++k;
    }
    if (meas.opencv) {
      meas.opencv->measure(frame.view());
      const auto rd = meas.opencv->results();
      for (std::size_t e = 0; e < rd.size(); ++e)
        score(k, e, rd[e].contact, rd[e].x_px, rd[e].y_px);
    }
  }
  const Bound crb = cramer_rao(s, radius, kReferenceFrames);
  std::vector<AccuracyRow> rows;
  std::size_t k = 0;
  const auto row_for = [&](const Method& m) {
    AccuracyRow r;
    r.method = m.name;
    r.setting = s;
    r.frames = frames;
    r.samples = stats[k].samples();
    r.misses = stats[k].misses();
    r.rms_x = stats[k].rms_x();
    r.rms_y = stats[k].rms_y();
    r.bias = stats[k].bias();
    r.bias_se = stats[k].bias_se();
    r.crb = crb;
    r.crb_simple = cramer_rao_simple(s);
    ++k;
    return r;
  };
  for (const auto& core : meas.cores)
    rows.push_back(row_for(*core.method));
  if (meas.opencv) rows.push_back(row_for(*meas.opencv_method));
  return rows;
}

// --- slips --------------------------------------------------------------------------------------

namespace {

struct SlipScene {
  testing::SceneOptions o;
  Calibration cal;
  std::unique_ptr<Measurers> meas;
  std::unique_ptr<testing::SceneRenderer> renderer;
};

SlipScene slip_scene(const std::vector<Method>& methods, double noise_sigma, util::Random& rng) {
  SlipScene sc;
  sc.o.noise_sigma = noise_sigma;
  // The calibration's contact thresholds (400 and 250 gray levels), raised where the noise
  // alone would reach them, as a calibration for that camera would (the rig does the same).
  const auto make_cal = [&](double floor_sigmas) {
    Calibration cal = dome_calibration(sc.o, 14.0, floor_sigmas);
    const auto pixels =
        static_cast<double>(disk_pixel_count(cal.elements[0].center_px, cal.elements[0].radius_px));
    const double noise = noise_sigma * std::sqrt(2.0);
    const auto [mean, sd] = noise_g(pixels, noise, cal.noise_floor / noise);
    cal.contact_on = std::max(cal.contact_on, std::ceil(mean + 8 * sd));
    cal.contact_off = std::max(cal.contact_off, 0.6 * cal.contact_on);
    return cal;
  };
  sc.cal = make_cal(2.0);
  sc.meas = std::make_unique<Measurers>(methods, sc.o, make_cal);
  sc.renderer = std::make_unique<testing::SceneRenderer>(sc.o, &sc.cal);
  std::vector<Image> reference(kReferenceFrames);
  for (int attempt = 0; attempt < 5; ++attempt) {
    for (Image& r : reference)
      sc.renderer->render({}, rng, r);
    if (sc.meas->reference(reference)) break;
  }
  return sc;
}

// Per-frame displacement magnitude (mm) and whether there is one, for method k, element e.
struct Disp {
  bool has = false;
  double mm = 0;
  double x_px = 0;
  double y_px = 0;
};

// The OpenCV baseline has no displacement of its own: the difference of its centroids between
// consecutive frames, as a user would compute it.
struct OpenCvTrack {
  std::vector<Disp> last;
};

std::vector<std::vector<Disp>> measure_slip_frame(SlipScene& sc, const Image& frame,
                                                  std::uint64_t seq, OpenCvTrack& track) {
  std::vector<std::vector<Disp>> out;
  for (auto& core : sc.meas->cores) {
    core.ex->measure(frame.view(), {seq, 0});
    std::vector<Disp> d;
    for (const ElementReading& r : core.ex->readings())
      d.push_back({r.has_displacement, std::hypot(r.dx_mm, r.dy_mm), r.x_px, r.y_px});
    out.push_back(std::move(d));
  }
  if (sc.meas->opencv) {
    sc.meas->opencv->measure(frame.view());
    const auto rd = sc.meas->opencv->results();
    std::vector<Disp> d(rd.size());
    if (track.last.size() != rd.size()) track.last.assign(rd.size(), Disp{});
    for (std::size_t e = 0; e < rd.size(); ++e) {
      d[e].x_px = rd[e].x_px;
      d[e].y_px = rd[e].y_px;
      d[e].has = rd[e].contact && track.last[e].has;
      if (d[e].has) {
        d[e].mm = std::hypot(rd[e].x_px - track.last[e].x_px, rd[e].y_px - track.last[e].y_px) *
                  sc.cal.mm_per_px;
      }
      track.last[e] = {rd[e].contact, 0, rd[e].x_px, rd[e].y_px};
    }
    out.push_back(std::move(d));
  }
  return out;
}

std::vector<std::string> names(const SlipScene& sc) {
  std::vector<std::string> n;
  for (const auto& c : sc.meas->cores)
    n.push_back(c.method->name);
  if (sc.meas->opencv) n.push_back(sc.meas->opencv_method->name);
  return n;
}

}  // namespace

std::vector<FalseSlipRow> run_false_slips(const std::vector<Method>& methods, double noise_sigma,
                                          double peak, int frames, std::uint64_t seed) {
  util::Random rng(seed);
  SlipScene sc = slip_scene(methods, noise_sigma, rng);
  std::vector<testing::Spot> spots;
  for (const ElementCalibration& e : sc.cal.elements) {
    testing::Spot s;
    s.center = e.center_px + Vec2{rng.uniform(-1, 1), rng.uniform(-1, 1)};
    s.peak = peak;
    s.sigma = 2.5;
    spots.push_back(s);
  }
  const std::vector<std::string> n = names(sc);
  std::vector<FalseSlipRow> rows(n.size());
  // Per method and element: sums of x, x^2, y, y^2 for the centroid's frame-to-frame spread.
  std::vector<std::vector<std::array<double, 5>>> mom(
      n.size(), std::vector<std::array<double, 5>>(sc.cal.elements.size()));
  Image frame;
  OpenCvTrack track;
  for (int f = 0; f < frames; ++f) {
    sc.renderer->render(spots, rng, frame);
    const auto d = measure_slip_frame(sc, frame, static_cast<std::uint64_t>(f), track);
    for (std::size_t k = 0; k < d.size(); ++k) {
      for (std::size_t e = 0; e < d[k].size(); ++e) {
        if (d[k][e].has) {
          ++rows[k].element_frames;
          if (d[k][e].mm > kDrMm) ++rows[k].false_slips;
        }
        auto& m = mom[k][e];
        m[0] += 1;
        m[1] += d[k][e].x_px;
        m[2] += d[k][e].x_px * d[k][e].x_px;
        m[3] += d[k][e].y_px;
        m[4] += d[k][e].y_px * d[k][e].y_px;
      }
    }
  }
  const double dr_px = kDrMm / sc.cal.mm_per_px;
  for (std::size_t k = 0; k < n.size(); ++k) {
    double var = 0;
    for (const auto& m : mom[k]) {
      const double vx = m[2] / m[0] - (m[1] / m[0]) * (m[1] / m[0]);
      const double vy = m[4] / m[0] - (m[3] / m[0]) * (m[3] / m[0]);
      var += (std::max(vx, 0.0) + std::max(vy, 0.0)) / 2;
    }
    rows[k].method = n[k];
    rows[k].noise_sigma = noise_sigma;
    rows[k].peak = peak;
    rows[k].centroid_sigma_px = std::sqrt(var / static_cast<double>(mom[k].size()));
    const double sc2 = rows[k].centroid_sigma_px * rows[k].centroid_sigma_px;
    rows[k].predicted = sc2 > 0 ? std::exp(-dr_px * dr_px / (4 * sc2)) : 0;
  }
  return rows;
}

std::vector<DelayRow> run_delays(const std::vector<Method>& methods, double speed_dr, int trials,
                                 std::uint64_t seed) {
  util::Random rng(seed);
  SlipScene sc = slip_scene(methods, 2.0, rng);
  const std::vector<std::string> n = names(sc);
  const std::size_t ne = sc.cal.elements.size();
  constexpr int kStill = 5;
  const double step_px = speed_dr * kDrMm / sc.cal.mm_per_px;
  // Up to 10 moving frames, fewer for fast slips so that the spot travels at most 8 px and
  // stays well inside its disk.
  const int kMoving = std::clamp(static_cast<int>(8.0 / step_px), 3, 10);
  std::vector<DelayRow> rows(n.size());
  std::vector<std::vector<double>> delays(n.size());
  Image frame;
  std::uint64_t seq = 0;
  const int rounds = std::max(1, (trials + static_cast<int>(ne) - 1) / static_cast<int>(ne));
  for (int t = 0; t < rounds; ++t) {
    std::vector<testing::Spot> spots(ne);
    std::vector<Vec2> dir(ne);
    for (std::size_t e = 0; e < ne; ++e) {
      spots[e].center = sc.cal.elements[e].center_px + Vec2{rng.uniform(-1, 1), rng.uniform(-1, 1)};
      spots[e].peak = 100;
      spots[e].sigma = 2.5;
      const double a = rng.uniform(0, 2 * std::numbers::pi);
      dir[e] = {std::cos(a), std::sin(a)};
      // Start far enough back that the spot ends where it started, inside the disk.
      spots[e].center = spots[e].center - (kMoving * step_px / 2) * dir[e];
    }
    for (auto& core : sc.meas->cores)
      core.ex->forget_previous();
    OpenCvTrack track;
    std::vector<std::vector<int>> detected(n.size(), std::vector<int>(ne, 0));
    std::vector<std::vector<bool>> early(n.size(), std::vector<bool>(ne, false));
    for (int f = 0; f < kStill + kMoving; ++f) {
      if (f >= kStill) {
        for (std::size_t e = 0; e < ne; ++e)
          spots[e].center = spots[e].center + step_px * dir[e];
      }
      sc.renderer->render(spots, rng, frame);
      const auto d = measure_slip_frame(sc, frame, seq++, track);
      for (std::size_t k = 0; k < d.size(); ++k) {
        for (std::size_t e = 0; e < ne; ++e) {
          const bool slip = d[k][e].has && d[k][e].mm > kDrMm;
          if (!slip) continue;
          if (f < kStill) {
            // Only the frames after the first one count (the first has no predecessor).
            early[k][e] = true;
          } else if (detected[k][e] == 0) {
            detected[k][e] = f - kStill + 1;
          }
        }
      }
    }
    for (std::size_t k = 0; k < n.size(); ++k) {
      for (std::size_t e = 0; e < ne; ++e) {
        DelayRow& r = rows[k];
        ++r.trials;
        if (early[k][e]) ++r.early;
        const int dl = detected[k][e];
        if (dl == 0) {
          ++r.undetected;
          delays[k].push_back(kMoving + 1);
          continue;
        }
        if (dl <= 1) ++r.within_1;
        if (dl <= 2) ++r.within_2;
        delays[k].push_back(dl);
      }
    }
    seq += 10;  // a gap: the next trial starts without a predecessor
  }
  for (std::size_t k = 0; k < n.size(); ++k) {
    rows[k].method = n[k];
    rows[k].speed_dr = speed_dr;
    rows[k].p50 = util::nearest_rank_percentile(delays[k], 0.5);
    rows[k].p99 = util::nearest_rank_percentile(delays[k], 0.99);
    rows[k].max = util::nearest_rank_percentile(delays[k], 1.0);
  }
  return rows;
}

}  // namespace tactile::bench
