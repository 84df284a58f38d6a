// tactile_mcap: a tactile log (docs/recording.md) exported to MCAP for Foxglove and PlotJuggler
// (docs/recording.md#mcap-export, docs/tools.md).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <string>

#include "tactile/cli/run.hpp"
#include "tactile/mcap/export.hpp"
#include "tactile/recording/read_progress.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/stop.hpp"

namespace {

struct Options {
  std::string in;
  std::string out;
  std::string compression = "zstd";
  std::size_t chunk_kib = 1024;
  double progress_s = 2.0;
  bool overwrite = false;
  std::string log_level = "info";
};

int run(const Options& opt) {
  tactile::util::set_log_level(tactile::util::parse_log_level(opt.log_level));
  tactile::mcap::ExportOptions eo;
  eo.writer.compression = tactile::mcap::parse_compression(opt.compression);
  if (opt.chunk_kib == 0) throw std::invalid_argument("--chunk-kib must be positive");
  eo.writer.chunk_bytes = opt.chunk_kib << 10;
  eo.writer.library = "tactile_mcap 0.1.0";
  if (!opt.overwrite && std::filesystem::exists(opt.out))
    throw std::runtime_error(opt.out + ": exists (give --overwrite to replace it)");
  tactile::recording::LogReader in(opt.in);
  tactile::util::install_stop_handlers();
  tactile::util::AtomicFileWriter out(opt.out);
  tactile::recording::ReadProgress progress(in, static_cast<std::int64_t>(opt.progress_s * 1e9));
  eo.progress = [&](const tactile::recording::LogReader&, std::uint64_t records) {
    if (tactile::util::stop_requested()) return false;
    progress.tick(records);
    return true;
  };
  const auto result = tactile::mcap::export_log(
      in, [&](std::string_view bytes) { out.write(bytes); }, eo);
  if (result.stopped) {
    tactile::util::log_info("stopped after {} records: {} not written", result.records, opt.out);
    return tactile::util::interrupted_exit_status();  // `out` removes its temporary file
  }
  if (result.end == tactile::recording::ReadStatus::kCorrupt) {
    std::fprintf(stderr, "tactile_mcap: %s (nothing written)\n", in.problem().c_str());
    return 1;
  }
  out.commit();
  if (result.end == tactile::recording::ReadStatus::kTruncated)
    tactile::util::log_warn("{}", in.problem());
  if (result.skipped > 0)
    tactile::util::log_warn("{} records do not decode and were left out; the first: {}",
                            result.skipped, result.skip_problem);
  std::string topics;
  for (const auto& [topic, n] : result.per_topic)
    topics += (topics.empty() ? "" : ", ") + topic + " " + std::to_string(n);
  tactile::util::log_info("{}: {} messages in {} chunks ({})", opt.out, result.messages,
                          result.chunks, topics.empty() ? "no messages" : topics);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("tactile_mcap");
  Options opt;
  CLI::App app{
      "Exports a tactile log (tactile_record, docs/recording.md) to an MCAP file that Foxglove and "
      "PlotJuggler open: one channel per topic, each Envelope unwrapped to the message it carries "
      "(TactileFrame, Event, GroundTruth...), raw frames as RawFrame, the protobuf schemas "
      "embedded. The output appears whole or not at all (a temporary file renamed at the end)."};
  app.add_option("in", opt.in, "the log file (.tlog)")->required();
  app.add_option("out", opt.out, "the MCAP file to write (.mcap)")->required();
  app.add_option("--compression", opt.compression, "chunk compression: zstd or none")
      ->capture_default_str();
  app.add_option("--chunk-kib", opt.chunk_kib, "uncompressed size of a chunk")
      ->capture_default_str();
  app.add_option("--progress", opt.progress_s, "log progress every this many seconds (0: never)")
      ->capture_default_str();
  app.add_flag("--overwrite", opt.overwrite, "replace an existing output file");
  tactile::cli::add_log_level(app, opt.log_level);
  return tactile::cli::run(app, argc, argv, [&] { return run(opt); });
}
