// The training rows file (docs/slip.md, "Training on a cluster").
#include "tactile/rig/training_rows.hpp"

#include <fmt/format.h>

#include <bit>
#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace tactile::rig::train {
namespace {

constexpr std::string_view kFormat = "tactile-slip-rows/1";
static_assert(std::endian::native == std::endian::little,
              "the rows file stores little-endian bytes as they are in memory");

template <typename T>
void put(std::string& out, const T* data, std::size_t count) {
  // An empty run's vectors may hold no storage at all (data() null): nothing to copy.
  if (count == 0) return;
  out.append(reinterpret_cast<const char*>(data), count * sizeof(T));
}

// Reads the binary part in order; a file that ends early is an error naming the source.
class Reader {
 public:
  Reader(std::string_view bytes, const std::string& source) : bytes_(bytes), source_(source) {}
  template <typename T>
  void get(T* data, std::size_t count) {
    const std::size_t n = count * sizeof(T);
    if (n / sizeof(T) != count || bytes_.size() - at_ < n)
      throw std::runtime_error(source_ + ": the file ends within a run's rows (cut short?)");
    if (n == 0) return;  // data may be null (an empty vector's)
    std::memcpy(data, bytes_.data() + at_, n);
    at_ += n;
  }
  std::uint64_t u64() {
    std::uint64_t v = 0;
    get(&v, 1);
    return v;
  }
  bool at_end() const { return at_ == bytes_.size(); }
  std::size_t left() const { return bytes_.size() - at_; }
  void skip_to(std::size_t at) { at_ = at; }

 private:
  std::string_view bytes_;
  const std::string& source_;
  std::size_t at_ = 0;
};

}  // namespace

std::string rows_file(const TrainingRows& rows) {
  nlohmann::ordered_json header = {{"format", kFormat},
                                   {"seeds", rows.seeds},
                                   {"scenarios", rows.scenarios},
                                   {"max_time_s", rows.max_time_s},
                                   {"controller", rows.controller},
                                   {"grip", rows.grip},
                                   {"features", rows.features},
                                   {"shard", rows.shard},
                                   {"shards", rows.shards},
                                   {"runs", rows.runs.size()}};
  if (!rows.calibration.empty()) header["calibration"] = rows.calibration;
  if (rows.sensor != "rig") header["sensor"] = rows.sensor;
  std::string out = header.dump() + "\n";
  for (const RowsOfRun& r : rows.runs) {
    if (r.x.size() != r.label.size() * rows.features || r.weight.size() != r.label.size()) {
      throw std::invalid_argument(
          fmt::format("seed {} scenario {}: {} features, {} labels, {} "
                      "weights do not make rows of {} features",
                      r.seed, r.index, r.x.size(), r.label.size(), r.weight.size(), rows.features));
    }
    const std::uint64_t head[3] = {r.seed, r.index, r.label.size()};
    put(out, head, 3);
    put(out, r.x.data(), r.x.size());
    put(out, r.label.data(), r.label.size());
    put(out, r.weight.data(), r.weight.size());
  }
  return out;
}

TrainingRows parse_rows_file(std::string_view bytes, const std::string& source) {
  const auto nl = bytes.find('\n');
  if (nl == std::string_view::npos)
    throw std::runtime_error(source + ": not a training rows file (no header line)");
  TrainingRows rows;
  std::size_t runs = 0;
  try {
    const nlohmann::json h = nlohmann::json::parse(bytes.substr(0, nl));
    if (h.at("format").get<std::string>() != kFormat) {
      throw std::runtime_error(
          fmt::format("format '{}', not '{}'", h.at("format").get<std::string>(), kFormat));
    }
    rows.seeds = h.at("seeds").get<std::vector<std::uint64_t>>();
    rows.scenarios = h.at("scenarios").get<std::uint64_t>();
    rows.max_time_s = h.at("max_time_s").get<double>();
    rows.controller = h.at("controller").get<std::string>();
    rows.grip = h.value("grip", std::string("paper"));
    rows.calibration = h.value("calibration", std::string());
    rows.sensor = h.value("sensor", std::string("rig"));
    rows.features = h.at("features").get<std::size_t>();
    rows.shard = h.at("shard").get<int>();
    rows.shards = h.at("shards").get<int>();
    runs = h.at("runs").get<std::size_t>();
    if (rows.features < 1 || rows.features > 4096)
      throw std::runtime_error(fmt::format("{} features per row", rows.features));
  } catch (const std::exception& e) {
    throw std::runtime_error(source + ": bad header: " + e.what());
  }
  Reader in(bytes, source);
  in.skip_to(nl + 1);
  for (std::size_t k = 0; k < runs; ++k) {
    RowsOfRun r;
    r.seed = in.u64();
    r.index = in.u64();
    const std::uint64_t n = in.u64();
    // A row takes features floats, a label and a weight: more rows than the file could hold are
    // a bad count, refused before anything is allocated for them.
    if (n > in.left() / (rows.features * sizeof(float) + 1 + sizeof(float)))
      throw std::runtime_error(fmt::format(
          "{}: the file ends within a run's rows (cut short?): run {} has {} rows", source, k, n));
    r.x.resize(n * rows.features);
    r.label.resize(n);
    r.weight.resize(n);
    in.get(r.x.data(), r.x.size());
    in.get(r.label.data(), r.label.size());
    in.get(r.weight.data(), r.weight.size());
    rows.runs.push_back(std::move(r));
  }
  if (!in.at_end())
    throw std::runtime_error(source + ": bytes after the last of its runs (not one file?)");
  return rows;
}

}  // namespace tactile::rig::train
