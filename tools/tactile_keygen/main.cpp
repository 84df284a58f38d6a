// tactile_keygen: makes ZeroMQ CURVE key pairs for the secured links (docs/security.md).
#include <CLI/CLI.hpp>
#include <cstdio>

#include "tactile/cli/run.hpp"
#include "tactile/util/log.hpp"
#include "tactile/wire/security.hpp"

int main(int argc, char** argv) {
  tactile::util::set_program_name("tactile_keygen");
  std::string dir = ".";
  std::vector<std::string> names;
  CLI::App app{
      "Makes ZeroMQ CURVE key pairs: for each NAME, DIR/NAME.key (the key pair, readable by its "
      "owner "
      "only) and DIR/NAME.pub (the public key, to give to the peers). Never overwrites a file."};
  app.add_option("--dir", dir, "folder for the key files")->capture_default_str();
  app.add_option("names", names, "key names, e.g. sensor hand arm")->required();
  return tactile::cli::run(app, argc, argv, [&] {
    if (!tactile::wire::curve_available())
      throw std::runtime_error("this libzmq was built without CURVE support");
    for (const auto& name : names) {
      tactile::wire::write_key_files(dir, name, tactile::wire::generate_keypair());
      std::fprintf(stderr, "tactile_keygen: wrote %s/%s.key (keep secret) and %s/%s.pub\n",
                   dir.c_str(), name.c_str(), dir.c_str(), name.c_str());
    }
    return 0;
  });
}
