// The fast per-frame path: exact G for elements out of contact (so no contact onset is ever
// missed), the AVX2 and portable kernels giving the same readings, and regions of interest
// measuring exactly what whole frames do.
#include <gtest/gtest.h>

#include <cmath>

#include "synthetic.hpp"
#include "tactile/extractor.hpp"

namespace tactile {
namespace {

using testing::SceneOptions;
using testing::Spot;

constexpr CentroidEstimator kAll[] = {CentroidEstimator::kPlain, CentroidEstimator::kThresholded,
                                      CentroidEstimator::kWindowed, CentroidEstimator::kGaussian,
                                      CentroidEstimator::kGaussianAxes};

SceneOptions scene(int depth) {
  SceneOptions o;
  o.width = 160;
  o.height = 120;
  o.bit_depth = depth;
  o.noise_sigma = 2;
  return o;
}

// G by definition, from an integer reference: sum over the disk of max(p - ref - floor, 0).
double g_by_hand(const Calibration& cal, std::size_t element, const Image& ref,
                 const Image& frame) {
  const ElementCalibration& e = cal.elements[element];
  double g = 0;
  for (const DiskRow& r : disk_rows(e.center_px, e.radius_px)) {
    for (int x = r.x0; x < r.x1; ++x) {
      const double d = static_cast<double>(frame.get(x, r.y)) - ref.get(x, r.y) - cal.noise_floor;
      g += std::max(d, 0.0);
    }
  }
  return g;
}

TEST(FastPath, OutOfContactGIsExact) {
  for (int depth : {8, 16}) {
    for (bool portable : {false, true}) {
      const SceneOptions o = scene(depth);
      Calibration cal = testing::grid_calibration(o, 4, 3, 36, 15);
      cal.noise_floor = 1.5 * testing::level_scale(depth);  // a fraction in Q8
      cal.contact_on = 1e5 * testing::level_scale(depth);   // noise never makes contact
      cal.contact_off = cal.contact_on / 2;
      ExtractorOptions opt;
      opt.reference_frames = 1;
      opt.portable_kernels = portable;
      Extractor ex(cal, opt);
      util::Random rng(5);
      Image ref;
      testing::render(o, {}, rng, ref);
      ASSERT_EQ(ex.add_reference_frame(ref.view()).status, ReferenceStatus::kComplete);
      for (std::uint64_t f = 0; f < 20; ++f) {
        Image frame;
        testing::render(o, {}, rng, frame);  // noise only: every element stays out of contact
        ASSERT_EQ(ex.measure(frame.view(), {f, 0}), MeasureStatus::kOk);
        for (std::size_t i = 0; i < cal.elements.size(); ++i) {
          ASSERT_FALSE(ex.readings()[i].contact);
          ASSERT_EQ(ex.readings()[i].G, g_by_hand(cal, i, ref, frame))
              << "depth " << depth << " element " << i;
        }
      }
    }
  }
}

TEST(FastPath, NoContactOnsetIsMissed) {
  // Single bright pixels and tiny spots anywhere in an idle element's disk: contact exactly when
  // the G of its pixels reaches contact.on, on the very frame they appear.
  for (bool portable : {false, true}) {
    const SceneOptions o = scene(8);
    Calibration cal = testing::grid_calibration(o, 4, 3, 36, 15);
    cal.contact_on = 60;
    cal.contact_off = 30;
    ExtractorOptions opt;
    opt.reference_frames = 1;
    opt.portable_kernels = portable;
    Extractor ex(cal, opt);
    Image ref(o.width, o.height, PixelFormat::kMono8);
    for (int y = 0; y < o.height; ++y)
      for (int x = 0; x < o.width; ++x)
        ref.set(x, y, 20);
    ASSERT_EQ(ex.add_reference_frame(ref.view()).status, ReferenceStatus::kComplete);
    util::Random rng(9);
    for (std::uint64_t f = 0; f < 400; ++f) {
      Image frame = ref;
      const std::size_t i = rng.below(cal.elements.size());
      const ElementCalibration& e = cal.elements[i];
      // A random pixel of the disk, brighter by 40 to 100 gray levels.
      const auto rows = disk_rows(e.center_px, e.radius_px);
      const DiskRow& r = rows[rng.below(rows.size())];
      const int x = r.x0 + static_cast<int>(rng.below(static_cast<std::uint64_t>(r.x1 - r.x0)));
      frame.set(x, r.y, 20 + 40 + static_cast<std::uint32_t>(rng.below(61)));
      ex.forget_previous();
      ASSERT_EQ(ex.measure(frame.view(), {f, 0}), MeasureStatus::kOk);
      const double g = g_by_hand(cal, i, ref, frame);
      ASSERT_EQ(ex.readings()[i].G, g);
      ASSERT_EQ(ex.readings()[i].contact, g >= cal.contact_on) << "frame " << f;
      if (ex.readings()[i].contact) {
        EXPECT_EQ(ex.readings()[i].x_px, x);
        EXPECT_EQ(ex.readings()[i].y_px, r.y);
      }
      // Back to the reference: out of contact again.
      ASSERT_EQ(ex.measure(ref.view(), {f + 1000000, 0}), MeasureStatus::kOk);
      ASSERT_FALSE(ex.readings()[i].contact);
    }
  }
}

// The readings of the AVX2 and the portable kernels: the same, but for the Gaussian estimators'
// floating-point rounding.
void expect_same_readings(const Extractor& fast, const Extractor& portable, CentroidEstimator est,
                          std::uint64_t frame) {
  for (std::size_t i = 0; i < fast.readings().size(); ++i) {
    const ElementReading& a = fast.readings()[i];
    const ElementReading& b = portable.readings()[i];
    ASSERT_EQ(a.contact, b.contact) << "frame " << frame << " element " << i;
    ASSERT_EQ(a.G, b.G) << "frame " << frame << " element " << i;
    if (est == CentroidEstimator::kGaussian || est == CentroidEstimator::kGaussianAxes) {
      ASSERT_NEAR(a.x_px, b.x_px, 1e-4) << "frame " << frame << " element " << i;
      ASSERT_NEAR(a.y_px, b.y_px, 1e-4) << "frame " << frame << " element " << i;
    } else {
      ASSERT_EQ(a.x_px, b.x_px) << to_string(est) << " frame " << frame << " element " << i;
      ASSERT_EQ(a.y_px, b.y_px) << to_string(est) << " frame " << frame << " element " << i;
    }
  }
}

TEST(FastPath, KernelSetsAgree) {
  // Spots of every size on elements of many radii (blocks of every width, some clipped at the
  // image's edge so they cannot be padded), both depths, every estimator.
  for (int depth : {8, 16}) {
    const SceneOptions o = scene(depth);
    Calibration cal = testing::grid_calibration(o, 4, 3, 38, 5);
    const double radii[] = {0.8, 2, 5, 9, 13, 16, 17.5, 18.4, 3.3, 7.7, 11, 14};
    for (std::size_t i = 0; i < cal.elements.size(); ++i) {
      cal.elements[i].radius_px = radii[i];
      cal.elements[i].center_px = cal.elements[i].center_px +
                                  Vec2{0.3 * static_cast<double>(i), -0.2 * static_cast<double>(i)};
      cal.elements[i].zero_px = cal.elements[i].center_px;
    }
    cal.elements[0].center_px = {0.5, 0.5};  // touching the corner
    cal.elements[0].zero_px = cal.elements[0].center_px;
    // Above what noise gives the largest disk (the reference capture's motion check uses it).
    cal.contact_on = 300 * testing::level_scale(depth);
    cal.contact_off = 150 * testing::level_scale(depth);
    for (CentroidEstimator est : kAll) {
      ExtractorOptions opt;
      opt.estimator = est;
      opt.reference_frames = 4;
      opt.reference_spot_check = false;
      Extractor fast(cal, opt);
      opt.portable_kernels = true;
      Extractor portable(cal, opt);
      util::Random rng(static_cast<std::uint64_t>(depth) * 10 + static_cast<std::uint64_t>(est));
      const testing::SceneRenderer renderer(o, &cal);
      Image img;
      for (int k = 0; k < 4; ++k) {
        renderer.render({}, rng, img);
        fast.add_reference_frame(img.view());
        portable.add_reference_frame(img.view());
      }
      ASSERT_TRUE(fast.has_reference());
      for (std::uint64_t f = 0; f < 30; ++f) {
        std::vector<Spot> spots;
        for (const ElementCalibration& e : cal.elements) {
          if (rng.uniform() < 0.3) continue;
          Spot s;
          s.center = e.center_px + Vec2{rng.uniform(-1, 1), rng.uniform(-1, 1)};
          s.sigma = rng.uniform(0.5, 4);
          s.peak = rng.uniform(10, 200);
          spots.push_back(s);
        }
        renderer.render(spots, rng, img);
        ASSERT_EQ(fast.measure(img.view(), {f, 0}), MeasureStatus::kOk);
        ASSERT_EQ(portable.measure(img.view(), {f, 0}), MeasureStatus::kOk);
        ASSERT_NO_FATAL_FAILURE(expect_same_readings(fast, portable, est, f));
      }
    }
  }
}

TEST(FastPath, KernelSetsAgreeOnEveryGaussianWindow) {
  // Large disks (blocks 96 columns wide) and spots from narrow to wide, near the centre and near
  // the edge: Gaussian windows of one to four groups of 8 inside the disk and reaching out of it,
  // and windows wider than 32 columns, each of which the AVX2 kernel sums its own way.
  SceneOptions o = scene(8);
  o.width = 320;
  o.height = 100;
  Calibration cal = testing::grid_calibration(o, 3, 1, 100, 40);
  // Above what noise gives disks this large (about 600 gray levels).
  cal.contact_on = 1500;
  cal.contact_off = 1000;
  ExtractorOptions opt;
  opt.estimator = CentroidEstimator::kGaussian;
  opt.reference_frames = 4;
  opt.reference_spot_check = false;
  Extractor fast(cal, opt);
  opt.portable_kernels = true;
  Extractor portable(cal, opt);
  util::Random rng(99);
  const testing::SceneRenderer renderer(o, &cal);
  Image img;
  for (int k = 0; k < 4; ++k) {
    renderer.render({}, rng, img);
    const ReferenceResult got = fast.add_reference_frame(img.view());
    ASSERT_TRUE(got.status == ReferenceStatus::kCollecting ||
                got.status == ReferenceStatus::kComplete)
        << to_string(got.status) << " element " << got.element_id << " value " << got.value;
    portable.add_reference_frame(img.view());
  }
  ASSERT_TRUE(fast.has_reference());
  int measured = 0;
  for (std::uint64_t f = 0; f < 200; ++f) {
    std::vector<Spot> spots;
    for (const ElementCalibration& e : cal.elements) {
      const double reach = rng.uniform() < 0.5 ? 3 : 28;
      Spot s;
      s.center = e.center_px + Vec2{rng.uniform(-reach, reach), rng.uniform(-reach, reach)};
      s.sigma = rng.uniform(2.2, 11);
      s.peak = rng.uniform(100, 200);
      spots.push_back(s);
    }
    renderer.render(spots, rng, img);
    ASSERT_EQ(fast.measure(img.view(), {f, 0}), MeasureStatus::kOk);
    ASSERT_EQ(portable.measure(img.view(), {f, 0}), MeasureStatus::kOk);
    ASSERT_NO_FATAL_FAILURE(expect_same_readings(fast, portable, opt.estimator, f));
    for (const ElementReading& r : fast.readings())
      measured += r.contact ? 1 : 0;
  }
  EXPECT_GT(measured, 500);
}

TEST(RegionOfInterest, HoldsEveryDiskAndObeysTheSteps) {
  SceneOptions o = scene(8);
  o.width = 640;
  o.height = 480;
  Calibration cal = testing::grid_calibration(o, 3, 2, 60, 14);
  // Disks span columns 245.5 +- 60 +- 14 and rows 209.5..269.5 +- 14.
  const Region exact = region_of_interest(cal);
  int x0 = o.width, x1 = 0, y0 = o.height, y1 = 0;
  for (const ElementCalibration& e : cal.elements) {
    for (const DiskRow& r : disk_rows(e.center_px, e.radius_px)) {
      x0 = std::min(x0, r.x0);
      x1 = std::max(x1, r.x1);
      y0 = std::min(y0, r.y);
      y1 = std::max(y1, r.y + 1);
    }
  }
  EXPECT_EQ(exact, (Region{x0, y0, x1 - x0, y1 - y0}));

  RegionRules rules;
  rules.offset_x_step = 8;
  rules.width_step = 16;
  rules.offset_y_step = 2;
  rules.height_step = 4;
  const Region r = region_of_interest(cal, rules);
  EXPECT_EQ(r.x % 8, 0);
  EXPECT_EQ(r.width % 16, 0);
  EXPECT_EQ(r.y % 2, 0);
  EXPECT_EQ(r.height % 4, 0);
  EXPECT_LE(r.x, exact.x);
  EXPECT_LE(r.y, exact.y);
  EXPECT_GE(r.x + r.width, exact.x + exact.width);
  EXPECT_GE(r.y + r.height, exact.y + exact.height);
  EXPECT_LT(r.width, exact.width + 8 + 16);

  rules.full_width = true;
  const Region rows = region_of_interest(cal, rules);
  EXPECT_EQ(rows.x, 0);
  EXPECT_EQ(rows.width, o.width);
  EXPECT_EQ(rows.y, r.y);

  // Steps that cannot be met inside the image: that side falls back to the whole image.
  rules = {};
  rules.height_step = 500;  // taller than the image
  const Region whole = region_of_interest(cal, rules);
  EXPECT_EQ(whole.y, 0);
  EXPECT_EQ(whole.height, o.height);

  rules = {};
  rules.width_step = 0;
  EXPECT_THROW(region_of_interest(cal, rules), std::invalid_argument);
}

// What a camera applies with its own increments (AravisCamera at open): the smallest aligned
// region holding the one asked, never outside the image.
TEST(RegionOfInterest, AlignRegionGrowsToTheCamerasIncrementsInsideTheImage) {
  RegionRules rules;
  EXPECT_EQ(align_region({37, 21, 150, 101}, rules, 320, 240), (Region{37, 21, 150, 101}));
  rules.offset_x_step = 4;
  rules.offset_y_step = 2;
  rules.width_step = 16;
  rules.height_step = 8;
  // x 36 (multiple of 4) to 187 needs 151 columns: 160; y 20 to 122 needs 102 rows: 104.
  EXPECT_EQ(align_region({37, 21, 150, 101}, rules, 320, 240), (Region{36, 20, 160, 104}));
  // At the right edge the start moves left to keep the width a multiple of its step.
  EXPECT_EQ(align_region({300, 0, 20, 8}, rules, 320, 240), (Region{304 - 16, 0, 32, 8}));
  rules.full_width = true;
  EXPECT_EQ(align_region({37, 21, 150, 101}, rules, 320, 240), (Region{0, 20, 320, 104}));
  EXPECT_THROW(align_region({300, 0, 21, 8}, {}, 320, 240), std::invalid_argument);
  EXPECT_THROW(align_region({0, 0, 0, 8}, {}, 320, 240), std::invalid_argument);
  EXPECT_THROW(align_region({-1, 0, 8, 8}, {}, 320, 240), std::invalid_argument);
}

// A view of the region [r.x, r.x + w) x [r.y, r.y + h) of `full`, as a camera set to that region
// would deliver it (its own buffer, its own stride).
Image crop(const Image& full, const Region& r) {
  Image out(r.width, r.height, full.format());
  for (int y = 0; y < r.height; ++y)
    for (int x = 0; x < r.width; ++x)
      out.set(x, y, full.get(x + r.x, y + r.y));
  return out;
}

ImageView region_view(const Image& img, const Region& r) {
  ImageView v = img.view();
  v.origin_x = r.x;
  v.origin_y = r.y;
  return v;
}

TEST(RegionOfInterest, MeasuresExactlyWhatWholeFramesDo) {
  for (int depth : {8, 16}) {
    SceneOptions o = scene(depth);
    o.width = 320;
    o.height = 240;
    const Calibration cal = testing::grid_calibration(o, 3, 2, 40, 13);
    RegionRules rules;
    rules.offset_x_step = 4;
    rules.width_step = 8;
    const Region roi = region_of_interest(cal, rules);
    for (CentroidEstimator est : kAll) {
      ExtractorOptions opt;
      opt.estimator = est;
      opt.reference_frames = 3;
      Extractor whole(cal, opt);
      opt.accept_regions = true;
      Extractor part(cal, opt);
      util::Random rng(21);
      const testing::SceneRenderer renderer(o, nullptr);
      Image img;
      for (int k = 0; k < 3; ++k) {
        renderer.render({}, rng, img);
        whole.add_reference_frame(img.view());
        const Image c = crop(img, roi);
        part.add_reference_frame(region_view(c, roi));
      }
      ASSERT_TRUE(whole.has_reference());
      ASSERT_TRUE(part.has_reference());
      for (std::uint64_t f = 0; f < 10; ++f) {
        std::vector<Spot> spots;
        for (const ElementCalibration& e : cal.elements) {
          Spot s;
          s.center = e.center_px + Vec2{rng.uniform(-1, 1), rng.uniform(-1, 1)};
          s.peak = 80;
          s.sigma = 2;
          spots.push_back(s);
        }
        renderer.render(spots, rng, img);
        const Image c = crop(img, roi);
        ASSERT_EQ(whole.measure(img.view(), {f, 0}), MeasureStatus::kOk);
        ASSERT_EQ(part.measure(region_view(c, roi), {f, 0}), MeasureStatus::kOk);
        // The whole frame is fine for an extractor that accepts regions, too.
        for (std::size_t i = 0; i < cal.elements.size(); ++i) {
          const ElementReading& a = whole.readings()[i];
          const ElementReading& b = part.readings()[i];
          ASSERT_TRUE(a.contact);
          ASSERT_EQ(a.contact, b.contact);
          ASSERT_EQ(a.G, b.G);
          ASSERT_EQ(a.x_px, b.x_px) << to_string(est);
          ASSERT_EQ(a.y_px, b.y_px);
          ASSERT_EQ(a.dx_mm, b.dx_mm);
        }
      }
    }
  }
}

TEST(RegionOfInterest, RefusesViewsThatDoNotHoldEveryDisk) {
  SceneOptions o = scene(8);
  const Calibration cal = testing::grid_calibration(o, 3, 2, 40, 13);
  const Region roi = region_of_interest(cal);
  Image ref(o.width, o.height, PixelFormat::kMono8);
  ExtractorOptions opt;
  opt.reference_frames = 1;
  Extractor strict(cal, opt);
  opt.accept_regions = true;
  Extractor lenient(cal, opt);
  ASSERT_EQ(strict.add_reference_frame(ref.view()).status, ReferenceStatus::kComplete);
  ASSERT_EQ(lenient.add_reference_frame(ref.view()).status, ReferenceStatus::kComplete);

  const Image c = crop(ref, roi);
  // Without accept_regions a region is the wrong size.
  EXPECT_EQ(strict.measure(region_view(c, roi), {1, 0}), MeasureStatus::kWrongSize);
  EXPECT_EQ(lenient.measure(region_view(c, roi), {1, 0}), MeasureStatus::kOk);
  // One row short, one column short, shifted, or reaching beyond the sensor: refused.
  Region r = roi;
  r.height -= 1;
  EXPECT_EQ(lenient.measure(region_view(crop(ref, r), r), {2, 0}), MeasureStatus::kWrongSize);
  r = roi;
  r.x += 1;
  r.width -= 1;
  EXPECT_EQ(lenient.measure(region_view(crop(ref, r), r), {3, 0}), MeasureStatus::kWrongSize);
  Image wide(roi.width, roi.height, PixelFormat::kMono8);
  ImageView v = wide.view();
  v.origin_x = o.width - roi.width + 1;
  v.origin_y = roi.y;
  EXPECT_EQ(lenient.measure(v, {4, 0}), MeasureStatus::kWrongSize);
  v.origin_x = -1;
  EXPECT_EQ(lenient.measure(v, {5, 0}), MeasureStatus::kWrongSize);
  // A reference frame that is a region is refused by an extractor that does not accept them.
  EXPECT_EQ(strict.add_reference_frame(region_view(c, roi)).status, ReferenceStatus::kWrongSize);
}

}  // namespace
}  // namespace tactile
