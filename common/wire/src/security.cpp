#include "tactile/wire/security.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>
#include <zmq_addon.hpp>

#include "tactile/util/files.hpp"

namespace tactile::wire {
namespace {

constexpr std::size_t kZ85KeyLength = 40;

bool is_z85_key(const std::string& s) {
  if (s.size() != kZ85KeyLength) return false;
  std::array<std::uint8_t, 32> bin{};
  return zmq_z85_decode(bin.data(), s.c_str()) != nullptr;
}

std::string to_binary(const std::string& z85) {
  std::array<std::uint8_t, 32> bin{};
  if (zmq_z85_decode(bin.data(), z85.c_str()) == nullptr)
    throw std::invalid_argument("not a Z85 key");
  return std::string(reinterpret_cast<const char*>(bin.data()), bin.size());
}

// Lines "public: ..." and "secret: ..."; comments with #.
void parse_key_file(const std::filesystem::path& file, CurveKeyPair& out, bool need_secret) {
  std::string text;
  try {
    text = util::read_file(file);
  } catch (const std::exception& e) {
    throw std::runtime_error(e.what());
  }
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string key = line.substr(0, colon);
    std::string value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(" \t"));
    value.erase(value.find_last_not_of(" \t\r") + 1);
    if (key == "public") out.public_z85 = value;
    if (key == "secret") out.secret_z85 = value;
  }
  if (!is_z85_key(out.public_z85)) {
    throw std::runtime_error(file.string() + ": no valid 'public:' key (40 Z85 characters)");
  }
  if (need_secret && !is_z85_key(out.secret_z85)) {
    // Never quote the value: it may be most of a secret.
    throw std::runtime_error(file.string() + ": no valid 'secret:' key (40 Z85 characters)");
  }
}

void write_new(const std::filesystem::path& file, const std::string& content, mode_t mode) {
  if (std::filesystem::exists(file))
    throw std::runtime_error(file.string() + ": exists already; not overwritten");
  util::write_file_atomic(file, content);
  if (::chmod(file.c_str(), mode) != 0)
    throw std::runtime_error(file.string() + ": cannot set its permissions");
}

}  // namespace

bool curve_available() {
  return zmq_has("curve") != 0;
}

CurveKeyPair generate_keypair() {
  std::array<char, 41> pub{};
  std::array<char, 41> sec{};
  if (zmq_curve_keypair(pub.data(), sec.data()) != 0) {
    throw std::runtime_error("cannot generate a CURVE key pair: this libzmq has no CURVE support");
  }
  return {pub.data(), sec.data()};
}

void write_key_files(const std::filesystem::path& dir, const std::string& name,
                     const CurveKeyPair& keys) {
  std::filesystem::create_directories(dir);
  write_new(dir / (name + ".key"),
            "# ZeroMQ CURVE key pair of '" + name +
                "': keep this file secret (mode 0600)\npublic: " + keys.public_z85 +
                "\nsecret: " + keys.secret_z85 + "\n",
            0600);
  write_new(dir / (name + ".pub"),
            "# ZeroMQ CURVE public key of '" + name + "'\npublic: " + keys.public_z85 + "\n", 0644);
}

CurveKeyPair load_key_pair(const std::filesystem::path& key_file) {
  struct stat st {};
  if (::stat(key_file.c_str(), &st) != 0)
    throw std::runtime_error(key_file.string() + ": cannot open the key file");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw std::runtime_error(key_file.string() +
                             ": a secret key file must be readable by its owner only (mode " +
                             mode + "); run: chmod 600 " + key_file.string());
  }
  CurveKeyPair k;
  parse_key_file(key_file, k, true);
  return k;
}

std::string load_public_key(const std::filesystem::path& file) {
  CurveKeyPair k;
  parse_key_file(file, k, false);
  return k.public_z85;
}

namespace {
// ZAP domains. A context has one ZAP handler, and every CURVE server in it asks that handler: a
// server with no client list (a PUB that lets in whoever knows its public key) says so by its
// domain, so the arm's list in the same process does not shut out its subscribers.
constexpr std::string_view kListedDomain = "tactile";
constexpr std::string_view kOpenDomain = "tactile-open";
}  // namespace

void apply_server_security(zmq::socket_t& s, const ServerSecurity& sec) {
  s.set(zmq::sockopt::curve_server, true);
  s.set(zmq::sockopt::curve_secretkey, sec.keys.secret_z85);
  // Authentication requests go to the ZAP handler; without one the context admits every client.
  s.set(zmq::sockopt::zap_domain,
        std::string(sec.authorized_clients.empty() ? kOpenDomain : kListedDomain));
}

void apply_client_security(zmq::socket_t& s, const ClientSecurity& sec) {
  s.set(zmq::sockopt::curve_serverkey, sec.server_public_z85);
  s.set(zmq::sockopt::curve_publickey, sec.keys.public_z85);
  s.set(zmq::sockopt::curve_secretkey, sec.keys.secret_z85);
}

CurveAuthenticator::CurveAuthenticator(zmq::context_t& ctx,
                                       std::vector<std::string> authorized_clients_z85)
    : socket_(ctx, zmq::socket_type::rep) {
  for (const auto& k : authorized_clients_z85)
    allowed_.push_back(to_binary(k));
  socket_.set(zmq::sockopt::linger, 0);
  socket_.bind("inproc://zeromq.zap.01");
  thread_ = std::thread([this] { serve(); });
}

CurveAuthenticator::~CurveAuthenticator() {
  stop_ = true;
  thread_.join();
}

void CurveAuthenticator::serve() {
  // ZAP request: version, request id, domain, address, identity, mechanism, credentials...
  while (!stop_) {
    zmq::pollitem_t item{};
    item.socket = socket_.handle();
    item.events = ZMQ_POLLIN;
    try {
      if (zmq::poll(&item, 1, std::chrono::milliseconds(50)) <= 0) continue;
    } catch (const zmq::error_t&) {
      return;  // the context is closing
    }
    std::vector<zmq::message_t> parts;
    if (!zmq::recv_multipart(socket_, std::back_inserter(parts), zmq::recv_flags::dontwait) ||
        parts.size() < 6) {
      continue;
    }
    const std::string version = parts[0].to_string();
    const std::string request_id = parts[1].to_string();
    const std::string domain = parts[2].to_string();
    const std::string mechanism = parts[5].to_string();
    bool ok = false;
    if (version == "1.0" && mechanism == "CURVE" && parts.size() >= 7) {
      // A client of an open server has completed the handshake, so it knows the server's key.
      const std::string key = parts[6].to_string();
      ok = domain == kOpenDomain ||
           std::find(allowed_.begin(), allowed_.end(), key) != allowed_.end();
    }
    (ok ? accepted_ : refused_)++;
    const std::string code = ok ? "200" : "400";
    const std::string text = ok ? "OK" : "client key not authorized";
    // ZAP reply: version, request id, status code, status text, user id, metadata.
    const std::array<zmq::const_buffer, 6> reply{zmq::buffer(version), zmq::buffer(request_id),
                                                 zmq::buffer(code),    zmq::buffer(text),
                                                 zmq::str_buffer(""),  zmq::str_buffer("")};
    (void)zmq::send_multipart(socket_, reply);
  }
}

}  // namespace tactile::wire
