#pragma once

// ZeroMQ CURVE on both links (docs/security.md): sensor_node's PUB and the arm controller's
// ROUTER are CURVE servers; hand_node connects as a client that knows their public keys, and
// the arm controller lets in only the client keys it was given.
//
// Key files: NAME.key holds a key pair (Z85 text, mode 0600: readable by its owner only) and
// NAME.pub its public key. No function here ever puts a secret key into a message or a log.
#include <atomic>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>
#include <zmq.hpp>

namespace tactile::wire {

struct CurveKeyPair {
  std::string public_z85;  // 40 characters
  std::string secret_z85;  // 40 characters
};

bool curve_available();
CurveKeyPair generate_keypair();

// Writes DIR/NAME.key (0600) and DIR/NAME.pub (0644); refuses to overwrite existing files.
void write_key_files(const std::filesystem::path& dir, const std::string& name,
                     const CurveKeyPair& keys);
// Loads a key pair; throws std::runtime_error naming the file when it is missing, malformed, or
// readable or writable by anyone but its owner.
CurveKeyPair load_key_pair(const std::filesystem::path& key_file);
// Loads a public key (a .pub file, or the public half of a .key file).
std::string load_public_key(const std::filesystem::path& file);

// Security of a socket that binds (PUB, ROUTER).
struct ServerSecurity {
  CurveKeyPair keys;
  // Client public keys allowed in (Z85). Empty: any client that completes the CURVE handshake
  // (it must still know the server's public key).
  std::vector<std::string> authorized_clients;
};

// Security of a socket that connects (SUB, DEALER).
struct ClientSecurity {
  CurveKeyPair keys;
  std::string server_public_z85;
};

// Answers ZeroMQ's authentication requests (ZAP) for one context: CURVE clients whose public key
// is in the list are let in, every other request is refused and counted. A server secured with no
// client list (apply_server_security names it by its ZAP domain) lets in every CURVE client, which
// has proved by its handshake that it knows the server's public key. Bind the sockets it guards
// after making it; it stops when destroyed.
class CurveAuthenticator {
 public:
  CurveAuthenticator(zmq::context_t& ctx, std::vector<std::string> authorized_clients_z85);
  ~CurveAuthenticator();
  CurveAuthenticator(const CurveAuthenticator&) = delete;
  CurveAuthenticator& operator=(const CurveAuthenticator&) = delete;
  std::uint64_t accepted() const { return accepted_; }
  std::uint64_t refused() const { return refused_; }

 private:
  void serve();
  zmq::socket_t socket_;
  std::vector<std::string> allowed_;  // 32-byte binary keys
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> accepted_{0};
  std::atomic<std::uint64_t> refused_{0};
  std::thread thread_;
};

// Socket options (before bind or connect).
void apply_server_security(zmq::socket_t& s, const ServerSecurity& sec);
void apply_client_security(zmq::socket_t& s, const ClientSecurity& sec);

}  // namespace tactile::wire
