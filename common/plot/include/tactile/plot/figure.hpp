#pragma once

// Small plots written as PNG files: benchmark Pareto fronts, the paper's Fig. 10 (centroid change
// against fingertip position), Fig. 3-style shear vector fields, timelines of flags, forces and
// events, latency histograms. See docs/plot.md for pictures and an example.
//
// A Figure holds one or more panels stacked top to bottom; each panel has its own axes and its
// series. Build it, then render() or save_png():
//
//   tactile::plot::Figure fig(800, 500);
//   auto& p = fig.add_panel();
//   p.title("Centroid change").x_label("fingertip x [mm]").y_label("dy_G [mm]");
//   p.line(x, dy, "element 12");
//   fig.save_png("out/fig10.png");
//
// Data points that are not finite (NaN, infinity), or not positive on a log axis, are skipped:
// a line or step series breaks there instead of jumping across. Ranges come from the data unless
// set. Text is drawn in OpenCV's Hershey font, which covers printable ASCII only (other bytes
// show as '?'). Drawing is single-threaded and deterministic: the same figure gives the same
// pixels.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace tactile::plot {

struct Color {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
  friend bool operator==(const Color&, const Color&) = default;
};

inline constexpr Color kBlack{0, 0, 0};
inline constexpr Color kWhite{255, 255, 255};
inline constexpr Color kGray{128, 128, 128};

// The fixed palette series take their colours from, in order (10 colours, then it repeats):
// blue, orange, green, red, purple, brown, pink, gray, olive, cyan.
Color palette(std::size_t index);

enum class Scale : std::uint8_t { kLinear, kLog };

// kBest: the corner where the legend covers the fewest data points and labels.
enum class Corner : std::uint8_t { kTopRight, kTopLeft, kBottomRight, kBottomLeft, kBest };

// An axis range chosen from the data that matters rather than from every point: the
// [lo_quantile, hi_quantile] quantiles of the points' values (nearest rank), widened by `margin`
// times their span on each side. One outlier then no longer sets the scale; points beyond the
// range are drawn as markers at the edge of the axis and counted (PanelLayout::outliers).
struct RobustRange {
  double lo_quantile = 0.01;
  double hi_quantile = 0.99;
  double margin = 0.15;
};

// The robust range of `values` (non-finite values skipped); nullopt when none is finite.
// Throws std::invalid_argument for quantiles outside 0 <= lo <= hi <= 1 or a negative margin.
std::optional<std::pair<double, double>> robust_range(std::span<const double> values,
                                                      RobustRange r = {});

// How one series looks. Everything has a default: a series without a colour takes the next
// palette colour of its panel.
struct Style {
  std::optional<Color> color;
  int line_width = 2;      // pixels, lines, steps, arrows, circles and markers' outlines
  int marker_radius = 4;   // pixels, scatter points
  bool dashed = false;     // lines, steps, circles and vertical markers
  double arrow_scale = 1;  // arrows: drawn length = scale * (dx, dy), in data units
};

// One drawn thing, as the Panel methods below build it.
struct Series {
  enum class Kind : std::uint8_t {
    kLine,
    kScatter,
    kStep,
    kBars,
    kArrows,
    kVLine,
    kHLine,
    kCircle,
    kBand
  };
  Kind kind = Kind::kLine;
  std::vector<double> x;
  std::vector<double> y;
  std::vector<double> u;           // kBars: widths; kArrows: dx; kCircle: radius
  std::vector<double> v;           // kArrows: dy
  std::vector<std::string> texts;  // kScatter: point labels; kVLine, kHLine, kBand: the text
  // A histogram's values left out below its range and beyond it (drawn as a count at the edge).
  std::size_t below_range = 0;
  std::size_t beyond_range = 0;
  std::string label;  // legend entry ("" = none)
  Style style;
  Color color;
};

// One panel: axes, labels and series. Panels belong to a Figure (Figure::add_panel); every
// setter returns the panel so calls chain.
class Panel {
 public:
  // --- axes ------------------------------------------------------------------------------------
  Panel& title(std::string text);
  Panel& x_label(std::string text);
  Panel& y_label(std::string text);
  Panel& x_scale(Scale s);
  Panel& y_scale(Scale s);
  // A fixed range instead of one from the data (lo < hi; on a log axis both > 0). Throws
  // std::invalid_argument otherwise.
  Panel& x_range(double lo, double hi);
  Panel& y_range(double lo, double hi);
  // The y range from the data that matters (RobustRange) instead of every point: the quantiles
  // of the line, scatter and step points within the x range, together with every threshold
  // (hline, band) and bar. Points beyond it become outlier markers at the edge. A fixed end
  // (y_range) still wins.
  Panel& y_robust(RobustRange r = {});
  // With a fixed y range: points beyond it become markers at the edge too (on with y_robust).
  Panel& outlier_markers(bool on = true);
  // One data unit is as many pixels along x as along y (vector fields, circles): the axis that
  // would be stretched gets a wider range. Linear axes only; ignored on a log axis.
  Panel& equal_aspect(bool on = true);
  Panel& grid(bool on = true);  // light lines at the ticks; on by default
  // Where the legend goes (by default the corner where it covers the fewest data points and
  // labels); it lists every series with a label.
  Panel& legend(Corner where);
  Panel& no_legend();

  // --- series ----------------------------------------------------------------------------------
  // Every x/y pair of spans must have equal lengths (std::invalid_argument otherwise); empty
  // series are allowed and draw nothing. `label` names the series in the legend ("" = none).

  // Straight segments through the points in the order given.
  Panel& line(std::span<const double> x, std::span<const double> y, std::string label = {},
              Style style = {});
  // A filled dot per point; point_labels (empty, or one per point) are written beside the dots,
  // moved around a little so that they do not overlap each other.
  Panel& scatter(std::span<const double> x, std::span<const double> y, std::string label = {},
                 Style style = {}, std::vector<std::string> point_labels = {});
  // A staircase: y[i] holds from x[i] until x[i+1] (flags, states).
  Panel& step(std::span<const double> x, std::span<const double> y, std::string label = {},
              Style style = {});
  // Filled bars centred on x, `width` data units wide, from 0 (from the bottom edge on a log y
  // axis) to height.
  Panel& bars(std::span<const double> x, std::span<const double> height, double width,
              std::string label = {}, Style style = {});
  // Counts of `values` in `bins` equal bins over [lo, hi] (from the finite values when not
  // given; a value equal to hi goes in the last bin), drawn as bars. bins >= 1.
  Panel& histogram(std::span<const double> values, int bins, std::string label = {},
                   Style style = {}, std::optional<double> lo = std::nullopt,
                   std::optional<double> hi = std::nullopt);
  // The same over the robust range of the values (latencies with a rare long pause), kept within
  // the smallest and largest value: what lies outside is counted, not binned, and the count is
  // written at that edge of the axis.
  Panel& histogram(std::span<const double> values, int bins, RobustRange range,
                   std::string label = {}, Style style = {});
  // Arrows from (x, y) to (x + s dx, y + s dy), s = style.arrow_scale (a quiver plot).
  Panel& arrows(std::span<const double> x, std::span<const double> y, std::span<const double> dx,
                std::span<const double> dy, std::string label = {}, Style style = {});
  // A vertical line across the panel at x with `text` written beside its top (events).
  // Labels of markers close together are moved down so they stay readable.
  Panel& vline(double x, std::string text = {}, Style style = {});
  // A horizontal line across the panel at y (thresholds), with `text` at its right end.
  Panel& hline(double y, std::string text = {}, Style style = {});
  // A shaded horizontal band from y = lo to y = hi with dashed edges and `text` at its left end
  // (a threshold band such as +-dr). Drawn under every other series; always inside the range.
  Panel& band(double lo, double hi, std::string text = {}, Style style = {});
  // A circle of radius r (data units) around (cx, cy); round on screen with equal_aspect().
  Panel& circle(double cx, double cy, double r, std::string label = {}, Style style = {});

  struct Axis {
    std::string label;
    Scale scale = Scale::kLinear;
    std::optional<double> lo;
    std::optional<double> hi;
    std::optional<RobustRange> robust;  // y only
    bool outlier_markers = false;       // y only
  };
  // What the panel holds, as rendering reads it.
  const std::vector<Series>& series() const { return series_; }
  const Axis& x_axis() const { return x_; }
  const Axis& y_axis() const { return y_; }
  const std::string& title_text() const { return title_; }
  bool has_equal_aspect() const { return equal_aspect_; }
  bool has_grid() const { return grid_; }
  std::optional<Corner> legend_corner() const { return legend_; }

 private:
  Panel& add(Series s);
  Color next_color(const Style& style);

  std::string title_;
  Axis x_;
  Axis y_;
  bool equal_aspect_ = false;
  bool grid_ = true;
  std::optional<Corner> legend_ = Corner::kBest;
  std::vector<Series> series_;
  std::size_t colors_used_ = 0;
};

// Where a rendered panel's plot area lies in the picture and how data map onto it. Pixel
// coordinates: x the column, y the row, origin at the centre of the top-left pixel.
struct PanelLayout {
  int left = 0;                                   // first column inside the plot area
  int top = 0;                                    // first row inside the plot area
  int right = 0;                                  // one past the last column
  int bottom = 0;                                 // one past the last row
  double x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;  // axis ranges in data units
  Scale x_scale = Scale::kLinear;
  Scale y_scale = Scale::kLinear;
  std::vector<double> x_ticks;
  std::vector<double> y_ticks;
  // Points beyond the y range (y_robust, or outlier_markers with a fixed range), each drawn as a
  // small triangle on the edge it lies beyond, pointing out: at most one per column and edge.
  struct Outlier {
    double x_px = 0;
    double y_px = 0;  // the top row (above) or the bottom row (below) of the plot area
    bool above = false;
    Color color;  // the series'
  };
  std::vector<Outlier> outliers;
  std::size_t above = 0;  // points beyond the top, within the x range (all, not one per column)
  std::size_t below = 0;

  // Pixel position of a data value (NaN where it cannot be shown: not finite, or <= 0 on a log
  // axis). Values outside the range map outside the plot area.
  double x_px(double x) const;
  double y_px(double y) const;
};

// An RGB picture, rows top to bottom, 3 bytes per pixel.
struct Raster {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;
  Color at(int x, int y) const;
};

class Figure {
 public:
  // Picture size in pixels, each at least 64 (std::invalid_argument otherwise).
  explicit Figure(int width_px = 900, int height_px = 600);

  Figure& title(std::string text);
  // All panels use one x range (the union of their data, or the first panel's fixed range)
  // and only the bottom panel writes x tick labels and its x label (timelines).
  Figure& share_x(bool on = true);
  // Adds a panel below the others; relative_height > 0 sets its share of the height.
  Panel& add_panel(double relative_height = 1.0);
  Panel& panel(std::size_t index);
  std::size_t panel_count() const { return panels_.size(); }
  // A vertical marker at x in every panel; the text is written in the top panel only.
  Figure& mark(double x, std::string text = {}, Style style = {});

  // Sets the picture's height (the width stays) so that the equal-aspect panels' ranges fill
  // their plot areas instead of one axis being widened to keep the aspect: the panel that needs
  // the most height for its share gets exactly its ranges, the others a y range a little wider.
  // For a layout drawn to scale (a fingertip's elements) in a picture of another shape. The
  // height stays within 64..max_height_px; a figure without equal-aspect panels keeps its own.
  // Call it once the panels hold their series and ranges.
  Figure& fit_height_to_aspect(int max_height_px = 4000);

  int width() const { return width_; }
  int height() const { return height_; }

  // The layout render() uses, one entry per panel.
  std::vector<PanelLayout> layout() const;
  Raster render() const;
  // The picture as PNG file contents.
  std::string png() const;
  // Writes the PNG atomically (a temporary file renamed over `path`; missing directories are
  // created). Throws std::runtime_error naming `path` when it cannot.
  void save_png(const std::filesystem::path& path) const;

 private:
  int width_;
  int height_;
  std::string title_;
  bool share_x_ = false;
  std::deque<Panel> panels_;
  std::vector<double> weights_;
};

}  // namespace tactile::plot
