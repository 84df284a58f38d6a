// The measure step: frames taken under known loads -> samples, through the real measurement
// core with the sensor's layout, so the curves are fitted to exactly what sensor_node measures.
#include <fmt/format.h>

#include <map>
#include <stdexcept>

#include "calibrate.hpp"

namespace tactile::calibrate {

std::vector<Sample> measure_samples(const Calibration& cal, const std::vector<Image>& references,
                                    const std::vector<LoadRow>& loads,
                                    const std::function<Image(const std::string&)>& load_frame,
                                    const MeasureOptions& options, const Progress& progress) {
  if (references.empty()) throw std::invalid_argument("no reference frames given");
  ExtractorOptions xo;
  xo.estimator = options.estimator;
  xo.reference_spot_check = options.reference_spot_check;
  xo.reference_frames = static_cast<int>(references.size());
  Extractor ex(cal, xo);
  std::map<std::uint32_t, std::size_t> index;
  for (std::size_t i = 0; i < cal.elements.size(); ++i)
    index[cal.elements[i].id] = i;
  for (const LoadRow& row : loads) {
    if (!index.contains(row.element)) {
      throw std::runtime_error(fmt::format("{}: element {} is not in the calibration of '{}'",
                                           row.where, row.element, cal.sensor_id));
    }
  }
  ReferenceResult rr;
  for (std::size_t i = 0; i < references.size(); ++i) {
    const ImageView v = references[i].view();
    rr = ex.add_reference_frame(v);
    if (rr.status == ReferenceStatus::kWrongSize || rr.status == ReferenceStatus::kWrongFormat) {
      throw std::runtime_error(fmt::format(
          "reference {} is {}x{} {}-bit, the calibration needs {}x{} {}-bit", i + 1, v.width,
          v.height, bit_depth(v.format), cal.width, cal.height, cal.bit_depth));
    }
    if (rr.status != ReferenceStatus::kCollecting && rr.status != ReferenceStatus::kComplete) {
      throw std::runtime_error(fmt::format(
          "the reference was refused: {} (element {}, excess G {:.0f}); take it again with "
          "nothing touching the sensor, or use --no-reference-check for a sensor whose unloaded "
          "elements glow",
          to_string(rr.status), rr.element_id, rr.value));
    }
  }
  if (!ex.has_reference()) throw std::runtime_error("the reference did not complete");
  const Image blank = ex.reference_image();

  // Frames in the order they first appear; each read and measured once.
  std::vector<std::string> order;
  std::map<std::string, std::vector<std::size_t>> rows_of;
  for (std::size_t i = 0; i < loads.size(); ++i) {
    auto& rows = rows_of[loads[i].frame];
    if (rows.empty()) order.push_back(loads[i].frame);
    rows.push_back(i);
  }
  std::vector<Sample> out(loads.size());
  std::uint64_t seq = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::string& name = order[k];
    const Image frame = load_frame(name);
    // The blank frame ends every contact: contact is G >= contact.on in this frame alone.
    ex.measure(blank.view(), {seq, 0});
    const MeasureStatus status = ex.measure(frame.view(), {seq + 10, 0});
    seq += 20;
    if (status == MeasureStatus::kWrongSize || status == MeasureStatus::kWrongFormat) {
      throw std::runtime_error(
          fmt::format("{}: frame is {}x{} {}-bit, the calibration needs "
                      "{}x{} {}-bit",
                      name, frame.width(), frame.height(), bit_depth(frame.format()), cal.width,
                      cal.height, cal.bit_depth));
    }
    if (status != MeasureStatus::kOk) throw std::runtime_error(name + ": " + to_string(status));
    const auto readings = ex.readings();
    for (std::size_t i : rows_of[name]) {
      const LoadRow& row = loads[i];
      const ElementReading& r = readings[index.at(row.element)];
      Sample s;
      s.element = row.element;
      s.fz_n = row.fz_n;
      s.G = r.G;
      s.contact = r.contact;
      s.has_x = row.has_x;
      s.fx_n = row.fx_n;
      s.ux_mm = r.ux_mm;
      s.has_y = row.has_y;
      s.fy_n = row.fy_n;
      s.uy_mm = r.uy_mm;
      s.frame = name;
      s.where = row.where;
      out[i] = std::move(s);
    }
    if (progress) progress(k + 1, order.size(), "frames");
  }
  return out;
}

}  // namespace tactile::calibrate
