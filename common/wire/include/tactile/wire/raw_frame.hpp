#pragma once

// Raw camera frames on the wire and in logs (tactile.v1.RawFrame, docs/recording.md): conversion
// between an image view and the message, and between ExtractorOptions and the settings a
// REFERENCE frame carries. Pure functions: no sockets, no clocks. Their topic: raw_topic() in
// envelope.hpp.
#include <string>
#include <vector>

#include "tactile/extractor.hpp"
#include "tactile/image.hpp"
#include "tactile/v1/log.pb.h"

namespace tactile::wire {

// Copies the view's pixels and geometry into `out` (rows packed, 16-bit little-endian), reusing
// its buffers: no allocation once `out.pixels` has grown to the frame's size.
void fill_raw_pixels(const ImageView& view, v1::RawFrame& out);

// A view of a RawFrame's pixels. On a little-endian host it borrows `in.pixels`; otherwise 16-bit
// pixels are swapped into `scratch`. False, with `why`, when the geometry is not a Mono8/Mono16
// image whose pixel count matches the bytes.
bool raw_view(const v1::RawFrame& in, std::vector<std::uint8_t>& scratch, ImageView& out,
              std::string& why);

void fill_settings(const ExtractorOptions& options, v1::MeasurementSettings& out);
// Throws std::invalid_argument naming the estimator when it is not one the core knows.
ExtractorOptions to_options(const v1::MeasurementSettings& settings);

}  // namespace tactile::wire
