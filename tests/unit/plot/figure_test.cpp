// Figures: the PNG decodes to the requested size, series land on the pixels the layout
// promises, non-finite points are skipped, empty series are harmless, and a path that cannot be
// written is named in the error.
#include "tactile/plot/figure.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>

namespace tactile::plot {
namespace {

namespace fs = std::filesystem;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();
const Color kRed{220, 20, 20};
const Color kBlue{20, 40, 200};

// A fresh directory per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "plot_test.XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// A panel with fixed ranges [0, 10] x [0, 10], no grid and no legend: only what a test draws.
Panel& bare_panel(Figure& fig) {
  Panel& p = fig.add_panel();
  p.x_range(0, 10).y_range(0, 10).grid(false).no_legend();
  return p;
}

Style solid(Color c, int width = 3) {
  Style s;
  s.color = c;
  s.line_width = width;
  return s;
}

cv::Point px(const PanelLayout& l, double x, double y) {
  return {static_cast<int>(std::lround(l.x_px(x))), static_cast<int>(std::lround(l.y_px(y)))};
}

Color at(const Raster& r, cv::Point p) {
  return r.at(p.x, p.y);
}

TEST(Figure, PngDecodesToTheRequestedSize) {
  for (auto [w, h] : {std::pair{640, 360}, std::pair{300, 900}, std::pair{64, 64}}) {
    Figure fig(w, h);
    fig.title("size test");
    const std::vector<double> x{0, 1, 2, 3};
    const std::vector<double> y{1, 3, 2, 5};
    fig.add_panel().line(x, y, "a").x_label("x").y_label("y").title("t");
    const std::string bytes = fig.png();
    ASSERT_GT(bytes.size(), 8U);
    EXPECT_EQ(bytes.substr(1, 3), "PNG");
    const std::vector<std::uint8_t> buf(bytes.begin(), bytes.end());
    const cv::Mat img = cv::imdecode(buf, cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty());
    EXPECT_EQ(img.cols, w);
    EXPECT_EQ(img.rows, h);
  }
}

TEST(Figure, SavePngWritesAFileAtomically) {
  const TempDir dir;
  const fs::path file = dir.path() / "sub" / "plot.png";
  Figure fig(320, 240);
  const std::vector<double> v{1, 2, 3};
  fig.add_panel().scatter(v, v, "points", {}, {"a", "b", "c"});
  fig.save_png(file);
  const cv::Mat img = cv::imread(file.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 320);
  EXPECT_EQ(img.rows, 240);
  // The decoded file is the rendered picture, pixel for pixel.
  const Raster r = fig.render();
  for (int y = 0; y < r.height; y += 7) {
    for (int x = 0; x < r.width; x += 5) {
      const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
      ASSERT_EQ(r.at(x, y), (Color{p[2], p[1], p[0]})) << x << "," << y;
    }
  }
  // Nothing else is left beside it (no temporary file).
  int files = 0;
  for (const auto& e : fs::directory_iterator(file.parent_path())) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 1);
}

TEST(Figure, BadPathThrowsNamingThePath) {
  const TempDir dir;
  const fs::path blocker = dir.path() / "a_file";
  std::ofstream(blocker) << "x";
  const fs::path bad = blocker / "plot.png";  // a directory that cannot exist
  Figure fig(200, 150);
  fig.add_panel();
  try {
    fig.save_png(bad);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
  }
}

TEST(Figure, DiagonalLineLandsOnTheComputedPixels) {
  Figure fig(500, 400);
  const std::vector<double> x{0, 10};
  const std::vector<double> y{0, 10};
  bare_panel(fig).line(x, y, "", solid(kRed));
  const Raster r = fig.render();
  const PanelLayout l = fig.layout()[0];
  ASSERT_GT(l.right - l.left, 200);
  ASSERT_GT(l.bottom - l.top, 200);
  for (double t = 0.5; t < 10; t += 0.37) {
    EXPECT_EQ(at(r, px(l, t, t)), kRed) << "t " << t;
  }
  // Well off the line: background.
  EXPECT_EQ(at(r, px(l, 8, 2)), kWhite);
  EXPECT_EQ(at(r, px(l, 2, 8)), kWhite);
  // The mapping puts the range's ends on the plot area's first and last pixels.
  EXPECT_DOUBLE_EQ(l.x_px(0), l.left);
  EXPECT_DOUBLE_EQ(l.x_px(10), l.right - 1);
  EXPECT_DOUBLE_EQ(l.y_px(10), l.top);
  EXPECT_DOUBLE_EQ(l.y_px(0), l.bottom - 1);
}

TEST(Figure, HorizontalAndVerticalLinesFillTheirRowAndColumn) {
  Figure fig(400, 300);
  Panel& p = bare_panel(fig);
  p.hline(2.5, "", solid(kBlue, 1));
  p.vline(7.5, "", solid(kRed, 1));
  const Raster r = fig.render();
  const PanelLayout l = fig.layout()[0];
  const int row = static_cast<int>(std::lround(l.y_px(2.5)));
  const int col = static_cast<int>(std::lround(l.x_px(7.5)));
  int blue = 0;
  for (int x = l.left + 2; x < l.right - 2; ++x) {
    if (x == col) continue;
    const Color c = r.at(x, row);
    // Anti-aliasing may share a sub-pixel position between two rows; the nearer row is mostly
    // the line's colour.
    if (c.b > 150 && c.r < 150) ++blue;
  }
  EXPECT_GT(blue, (l.right - l.left) * 9 / 10);
  int red = 0;
  for (int y = l.top + 2; y < l.bottom - 2; ++y) {
    const Color c = r.at(col, y);
    if (c.r > 150 && c.b < 150) ++red;
  }
  EXPECT_GT(red, (l.bottom - l.top) * 9 / 10);
}

TEST(Figure, NonFinitePointsAreSkippedNotDrawn) {
  Figure fig(500, 400);
  const std::vector<double> x{0, 1, 2, 3, 4};
  const std::vector<double> y{0, 1, kNaN, 3, 4};
  bare_panel(fig).line(x, y, "", solid(kRed));
  const Raster r = fig.render();
  const PanelLayout l = fig.layout()[0];
  // Segment 0-1 and 3-4 are drawn ...
  EXPECT_EQ(at(r, px(l, 0.5, 0.5)), kRed);
  EXPECT_EQ(at(r, px(l, 3.5, 3.5)), kRed);
  // ... but nothing bridges the gap around the NaN point.
  EXPECT_EQ(at(r, px(l, 2, 2)), kWhite);
  EXPECT_EQ(at(r, px(l, 1.6, 1.6)), kWhite);
  EXPECT_EQ(at(r, px(l, 2.4, 2.4)), kWhite);
}

TEST(Figure, NonFiniteAndNonPositiveDataDoNotStretchTheRanges) {
  Figure fig(500, 400);
  const std::vector<double> x{1, 2, kInf, 3, -kInf, kNaN};
  const std::vector<double> y{5, 6, 7, kNaN, 8, 9};
  fig.add_panel().scatter(x, y);
  Panel& logp = fig.add_panel();
  logp.x_scale(Scale::kLog).y_scale(Scale::kLog);
  const std::vector<double> lx{-1, 0, 0.1, 10};
  const std::vector<double> ly{1, 1, 1, 100};
  logp.line(lx, ly);
  const std::vector<PanelLayout> l = fig.layout();
  // Linear: only (1, 5) and (2, 6) are whole points.
  EXPECT_GT(l[0].x_lo, 0.9);
  EXPECT_LT(l[0].x_hi, 2.1);
  EXPECT_GT(l[0].y_lo, 4.9);
  EXPECT_LT(l[0].y_hi, 6.1);
  // Log: -1 and 0 cannot be shown; the range covers 0.1 .. 10 only.
  EXPECT_GT(l[1].x_lo, 0.05);
  EXPECT_LT(l[1].x_hi, 20);
  EXPECT_TRUE(std::isnan(l[1].x_px(0)));
  EXPECT_TRUE(std::isnan(l[1].x_px(-1)));
  EXPECT_TRUE(std::isnan(l[0].x_px(kNaN)));
  // And rendering is fine.
  const Raster r = fig.render();
  EXPECT_EQ(r.width, 500);
}

TEST(Figure, EmptySeriesDoNotCrash) {
  const std::vector<double> none;
  Figure fig(300, 400);
  Panel& p = fig.add_panel();
  p.line(none, none, "line").scatter(none, none, "scatter", {}, {}).step(none, none, "step");
  p.bars(none, none, 1.0, "bars").histogram(none, 5, "hist").arrows(none, none, none, none, "q");
  Panel& q = fig.add_panel();
  q.x_scale(Scale::kLog).y_scale(Scale::kLog).line(none, none);
  fig.add_panel();  // no series at all
  const Raster r = fig.render();
  EXPECT_EQ(r.width, 300);
  EXPECT_EQ(r.height, 400);
  EXPECT_FALSE(fig.png().empty());
  // Without panels: a blank picture.
  Figure blank(100, 80);
  EXPECT_EQ(blank.render().at(50, 40), kWhite);
  EXPECT_FALSE(blank.png().empty());
}

TEST(Figure, LogAxesMapDecadesEvenly) {
  Figure fig(600, 400);
  Panel& p = fig.add_panel();
  p.x_scale(Scale::kLog).y_scale(Scale::kLog).x_range(1e-3, 10).y_range(1, 1e4);
  const std::vector<double> x{1e-2, 1};
  const std::vector<double> y{10, 1000};
  p.scatter(x, y, "", solid(kBlue));
  const PanelLayout l = fig.layout()[0];
  const double decade_x = (l.right - 1 - l.left) / 4.0;
  EXPECT_NEAR(l.x_px(1e-2), l.left + decade_x, 1e-9);
  EXPECT_NEAR(l.x_px(1), l.left + 3 * decade_x, 1e-9);
  EXPECT_NEAR(l.y_px(100), (l.top + l.bottom - 1) / 2.0, 1e-9);
  EXPECT_EQ(l.x_ticks, (std::vector<double>{1e-3, 1e-2, 1e-1, 1, 10}));
  EXPECT_EQ(l.y_ticks, (std::vector<double>{1, 10, 100, 1000, 10000}));
  const Raster r = fig.render();
  EXPECT_EQ(at(r, px(l, 1e-2, 10)), kBlue);
  EXPECT_EQ(at(r, px(l, 1, 1000)), kBlue);
}

TEST(Figure, StepHoldsEachValueUntilTheNextPoint) {
  Figure fig(500, 400);
  const std::vector<double> x{0, 5, 10};
  const std::vector<double> y{2, 8, 8};
  bare_panel(fig).step(x, y, "", solid(kRed));
  const Raster r = fig.render();
  const PanelLayout l = fig.layout()[0];
  EXPECT_EQ(at(r, px(l, 2.5, 2)), kRed);  // the first level
  EXPECT_EQ(at(r, px(l, 5, 5)), kRed);    // the riser
  EXPECT_EQ(at(r, px(l, 7.5, 8)), kRed);  // the second level
  EXPECT_EQ(at(r, px(l, 2.5, 5)), kWhite);
  EXPECT_EQ(at(r, px(l, 7.5, 2)), kWhite);
}

TEST(Figure, BarsAndHistogramFillFromZero) {
  Figure fig(500, 400);
  const std::vector<double> x{5};
  const std::vector<double> h{4};
  bare_panel(fig).bars(x, h, 2, "", solid(kBlue));
  const Raster r = fig.render();
  const PanelLayout l = fig.layout()[0];
  EXPECT_EQ(at(r, px(l, 5, 2)), kBlue);
  EXPECT_EQ(at(r, px(l, 5.5, 3.5)), kBlue);
  EXPECT_EQ(at(r, px(l, 5, 5)), kWhite);
  EXPECT_EQ(at(r, px(l, 7, 2)), kWhite);

  Figure hist(400, 300);
  const std::vector<double> v{0, 0.1, 0.2, 0.9, 1.0, kNaN, 7};
  hist.add_panel().histogram(v, 2, "", {}, 0.0, 1.0);
  const Series& s = hist.panel(0).series()[0];
  EXPECT_EQ(s.x, (std::vector<double>{0.25, 0.75}));
  EXPECT_EQ(s.y, (std::vector<double>{3, 2}));  // 1.0 belongs to the last bin; NaN and 7 out
  // Auto range of bars starts at 0.
  EXPECT_EQ(hist.layout()[0].y_lo, 0.0);
}

TEST(Figure, ArrowsCirclesAndMarkersDrawWhereAsked) {
  Figure fig(500, 500);
  Panel& p = bare_panel(fig);
  const std::vector<double> x{2};
  const std::vector<double> y{2};
  const std::vector<double> dx{3};
  const std::vector<double> dy{0};
  Style arrow = solid(kRed);
  arrow.arrow_scale = 2;  // drawn 6 units long
  p.arrows(x, y, dx, dy, "", arrow);
  p.circle(5, 6, 2, "", solid(kBlue));
  const Raster r = fig.render();
  const PanelLayout l = fig.layout()[0];
  EXPECT_EQ(at(r, px(l, 4, 2)), kRed);
  EXPECT_EQ(at(r, px(l, 7.6, 2)), kRed);
  EXPECT_EQ(at(r, px(l, 9, 2)), kWhite);  // beyond the scaled tip
  EXPECT_EQ(at(r, px(l, 7, 6)), kBlue);   // on the circle
  EXPECT_EQ(at(r, px(l, 5, 8)), kBlue);
  EXPECT_EQ(at(r, px(l, 5, 6)), kWhite);  // its centre
}

TEST(Figure, SharedXAlignsPanels) {
  Figure fig(600, 600);
  fig.share_x();
  const std::vector<double> t1{0, 1, 2};
  const std::vector<double> t2{5, 6, 12};
  const std::vector<double> v{0, 1, 0};
  fig.add_panel().step(t1, v, "flag");
  fig.add_panel(2.0).line(t2, v, "force").y_label("N");
  fig.add_panel().line(t1, v).x_label("time [s]");
  fig.mark(3, "slip");
  const auto l = fig.layout();
  ASSERT_EQ(l.size(), 3U);
  for (const PanelLayout& p : l) {
    EXPECT_EQ(p.left, l[0].left);
    EXPECT_EQ(p.right, l[0].right);
    EXPECT_EQ(p.x_lo, l[0].x_lo);
    EXPECT_EQ(p.x_hi, l[0].x_hi);
  }
  EXPECT_LE(l[0].x_lo, 0);
  EXPECT_GE(l[0].x_hi, 12);
  // Stacked without overlap, the middle one about twice as tall.
  EXPECT_LE(l[0].bottom, l[1].top);
  EXPECT_LE(l[1].bottom, l[2].top);
  const int h0 = l[0].bottom - l[0].top;
  const int h1 = l[1].bottom - l[1].top;
  EXPECT_NEAR(h1, 2 * h0, 2);
  // The marker is in every panel.
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(fig.panel(i).series().back().kind, Series::Kind::kVLine);
    EXPECT_EQ(fig.panel(i).series().back().x[0], 3);
  }
}

// The axis choice on data with outliers: a robust y range spans the bulk of the data, the two
// outliers become markers on the edges they lie beyond, and thresholds are always in range.
TEST(Figure, RobustRangeShowsTheBulkAndMarksOutliersOnTheEdge) {
  std::vector<double> x;
  std::vector<double> y;
  for (int i = 0; i < 200; ++i) {
    x.push_back(i);
    y.push_back(1.0 + 0.5 * std::sin(i * 0.3));
  }
  y[120] = 500;  // one pause of the machine
  y[40] = -300;  // and one the other way
  y[41] = kNaN;  // skipped, not counted
  Figure fig(600, 400);
  Panel& p = fig.add_panel();
  p.grid(false).no_legend().line(x, y, "", solid(kBlue)).y_robust();
  const PanelLayout l = fig.layout()[0];
  // Quantiles 1 % and 99 % of the bulk (0.5 .. 1.5) widened by 15 % of their span each side.
  EXPECT_GT(l.y_lo, 0.3);
  EXPECT_LT(l.y_lo, 0.5);
  EXPECT_GT(l.y_hi, 1.5);
  EXPECT_LT(l.y_hi, 1.7);
  EXPECT_EQ(l.above, 1U);
  EXPECT_EQ(l.below, 1U);
  ASSERT_EQ(l.outliers.size(), 2U);
  for (const PanelLayout::Outlier& o : l.outliers) {
    const double want_x = o.above ? l.x_px(120) : l.x_px(40);
    EXPECT_DOUBLE_EQ(o.x_px, want_x);
    EXPECT_EQ(o.y_px, o.above ? l.top : l.bottom - 1);  // on the edge, not off the picture
    EXPECT_EQ(o.color, kBlue);
  }
  // The markers are drawn: a dark triangle just inside the top edge above x = 120.
  const Raster r = fig.render();
  const int col = static_cast<int>(std::lround(l.x_px(120)));
  EXPECT_NE(r.at(col, l.top + 4), kWhite);
  const int col40 = static_cast<int>(std::lround(l.x_px(40)));
  EXPECT_NE(r.at(col40, l.bottom - 5), kWhite);  // and above x = 40 on the bottom edge

  // Without it, one outlier sets the scale: the bulk is a flat line in 1 % of the height.
  Figure plain(600, 400);
  plain.add_panel().line(x, y);
  EXPECT_GE(plain.layout()[0].y_hi, 500);
  EXPECT_TRUE(plain.layout()[0].outliers.empty());

  // A threshold outside the bulk is always shown; a fixed end still wins.
  Figure with_band(600, 400);
  with_band.add_panel().line(x, y).band(-3, 3, "+-dr").y_robust();
  EXPECT_LE(with_band.layout()[0].y_lo, -3);
  EXPECT_GE(with_band.layout()[0].y_hi, 3);
  EXPECT_EQ(with_band.layout()[0].above, 1U);
  Figure fixed(600, 400);
  fixed.add_panel().line(x, y).y_robust().y_range(0, 10);
  EXPECT_EQ(fixed.layout()[0].y_lo, 0);
  EXPECT_EQ(fixed.layout()[0].y_hi, 10);
  EXPECT_EQ(fixed.layout()[0].above, 1U);
  EXPECT_EQ(fixed.layout()[0].below, 1U);
}

TEST(Figure, RobustHistogramCountsWhatLiesBeyond) {
  std::vector<double> v;
  for (int i = 0; i < 1000; ++i)
    v.push_back(0.5 + 0.001 * i);  // 0.5 .. 1.5 ms
  v.push_back(48.0);               // one 48 ms pause
  Figure fig(500, 300);
  Panel& p = fig.add_panel();
  p.histogram(v, 20, RobustRange{0.0, 0.99, 0.1});
  const Series& s = p.series()[0];
  EXPECT_EQ(s.beyond_range, 1U);  // the pause; the top 1 % lies within the margin
  EXPECT_EQ(s.below_range, 0U);
  EXPECT_LT(fig.layout()[0].x_hi, 2.0);
  const auto r = robust_range(v, RobustRange{0.0, 1.0, 0.0});
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->first, 0.5);
  EXPECT_EQ(r->second, 48.0);
  EXPECT_FALSE(robust_range(std::vector<double>{kNaN}).has_value());
  EXPECT_THROW(robust_range(v, RobustRange{0.9, 0.1, 0.1}), std::invalid_argument);
  EXPECT_THROW(Figure(300, 300).add_panel().y_robust(RobustRange{0, 1, -1}), std::invalid_argument);
}

TEST(Figure, LegendGoesWhereItCoversTheLeastData) {
  // Data fill the top half: the legend goes to a bottom corner.
  std::vector<double> x;
  std::vector<double> y;
  for (int i = 0; i <= 100; ++i) {
    x.push_back(i);
    y.push_back(i % 2 == 0 ? 8 : 10);
  }
  Figure fig(500, 400);
  Panel& p = fig.add_panel();
  p.x_range(0, 100).y_range(0, 10).grid(false).line(x, y, "zigzag", solid(kBlue, 1));
  const Raster r = fig.render();
  const PanelLayout l = fig.layout()[0];
  // The legend's frame (light grey) is in the bottom half, not in the top right.
  int grey_bottom = 0;
  int grey_top = 0;
  for (int yy = l.top; yy < l.bottom; ++yy) {
    for (int xx = l.left; xx < l.right; ++xx) {
      if (r.at(xx, yy) == Color{190, 190, 190})
        ++(yy > (l.top + l.bottom) / 2 ? grey_bottom : grey_top);
    }
  }
  EXPECT_GT(grey_bottom, 20);
  EXPECT_EQ(grey_top, 0);
}

TEST(Figure, EqualAspectGivesEqualScales) {
  Figure fig(800, 400);
  Panel& p = fig.add_panel();
  const std::vector<double> x{-1, 1};
  const std::vector<double> y{-1, 1};
  p.scatter(x, y).equal_aspect();
  const PanelLayout l = fig.layout()[0];
  const double ux = (l.x_hi - l.x_lo) / (l.right - 1 - l.left);
  const double uy = (l.y_hi - l.y_lo) / (l.bottom - 1 - l.top);
  EXPECT_NEAR(ux, uy, 1e-12);
  EXPECT_LE(l.x_lo, -1);
  EXPECT_GE(l.x_hi, 1);
  EXPECT_LE(l.y_lo, -1);
  EXPECT_GE(l.y_hi, 1);
}

// Two square layouts stacked in a wide picture: equal aspect alone widens x to three times the
// data; fitted, the picture is as tall as the squares need and neither axis is widened.
TEST(Figure, FitHeightToAspectLetsEqualAspectPanelsFillTheirAxes) {
  Figure fig(600, 300);
  const std::vector<double> x{-1, 1};
  const std::vector<double> y{-1, 1};
  for (int i = 0; i < 2; ++i)
    fig.add_panel().scatter(x, y).x_range(-1.1, 1.1).y_range(-1.1, 1.1).equal_aspect();
  EXPECT_GT(fig.layout()[0].x_hi - fig.layout()[0].x_lo, 5.0);
  fig.fit_height_to_aspect();
  EXPECT_GT(fig.height(), 2 * 450);
  EXPECT_LT(fig.height(), 2 * 600);
  for (const PanelLayout& l : fig.layout()) {
    EXPECT_DOUBLE_EQ(l.x_lo, -1.1);
    EXPECT_DOUBLE_EQ(l.x_hi, 1.1);
    EXPECT_NEAR(l.y_lo, -1.1, 0.01);  // within a row of the range asked for
    EXPECT_NEAR(l.y_hi, 1.1, 0.01);
    EXPECT_GE(l.y_hi - l.y_lo, 2.2);
    const double ux = (l.x_hi - l.x_lo) / (l.right - 1 - l.left);
    const double uy = (l.y_hi - l.y_lo) / (l.bottom - 1 - l.top);
    EXPECT_NEAR(ux, uy, 1e-12);
  }
  // Capped, and a figure without equal-aspect panels keeps its height.
  Figure capped(600, 300);
  capped.add_panel().scatter(x, y).equal_aspect();
  EXPECT_EQ(capped.fit_height_to_aspect(400).height(), 400);
  Figure plain(600, 300);
  plain.add_panel().scatter(x, y);
  EXPECT_EQ(plain.fit_height_to_aspect().height(), 300);
}

TEST(Figure, RenderingIsDeterministic) {
  Figure fig(400, 300);
  const std::vector<double> x{0, 1, 2, 3};
  const std::vector<double> y{3, 1, 4, 1};
  fig.add_panel().line(x, y, "a").scatter(x, y, "b", {}, {"p", "q", "r", "s"});
  EXPECT_EQ(fig.render().rgb, fig.render().rgb);
}

TEST(Figure, RefusesBadArguments) {
  EXPECT_THROW(Figure(10, 500), std::invalid_argument);
  Figure fig(300, 200);
  Panel& p = fig.add_panel();
  const std::vector<double> two{1, 2};
  const std::vector<double> three{1, 2, 3};
  EXPECT_THROW(p.line(two, three), std::invalid_argument);
  EXPECT_THROW(p.scatter(two, two, "", {}, {"only one"}), std::invalid_argument);
  EXPECT_THROW(p.bars(two, two, 0), std::invalid_argument);
  EXPECT_THROW(p.histogram(two, 0), std::invalid_argument);
  EXPECT_THROW(p.x_range(1, 1), std::invalid_argument);
  EXPECT_THROW(p.y_range(0, kNaN), std::invalid_argument);
  p.x_scale(Scale::kLog);
  EXPECT_THROW(p.x_range(0, 10), std::invalid_argument);
  EXPECT_THROW(fig.add_panel(0), std::invalid_argument);
  EXPECT_THROW(fig.panel(5), std::out_of_range);
}

TEST(Palette, IsFixedAndCycles) {
  EXPECT_EQ(palette(0), (Color{31, 119, 180}));
  EXPECT_EQ(palette(10), palette(0));
  for (std::size_t i = 0; i < 10; ++i)
    for (std::size_t j = i + 1; j < 10; ++j)
      EXPECT_NE(palette(i), palette(j));
}

}  // namespace
}  // namespace tactile::plot
