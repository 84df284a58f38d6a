#pragma once

// The arm controller's side of the arm link as a library (docs/arm.md): a ROUTER that decodes and
// checks ArmCommands, keeps the peer and its deadman, answers with ArmStates and Heartbeats,
// refuses strangers and garbage (counted), speaks CURVE, and hands the commands to an ArmBackend,
// the one piece a lab writes for its arm (in the spirit of ros2_control's hardware interface:
// read the state, write a command, hold).
//
// Time is an argument: the caller's clock (CLOCK_REALTIME, util::realtime_ns, as the wire's
// timestamps). Configuration errors (a bad endpoint, a port in use, a bad deadman) throw from the
// constructor; the per-message calls never throw for what a client sends and allocate nothing.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "tactile/arm/arm_peer.hpp"
#include "tactile/v1/tactile.pb.h"
#include "tactile/wire/arm.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/security.hpp"
#include "tactile/wire/sockets.hpp"

namespace tactile::arm {

// What an arm must do for the server (docs/arm.md, "What the backend does"). Called from the
// server's thread only, never concurrently; each call gets the instant it is made for.
struct ArmBackend {
  virtual ~ArmBackend() = default;
  // The arm's state at `now_ns`: wrist pose, fingertips (wrist frame), the active segment and
  // whether it is done, holding, limit. The server fills `time_ns` when it is 0,
  // `last_command_sequence` and `deadman` itself.
  virtual wire::ArmStateData read(std::int64_t now_ns) = 0;
  // Follow a checked command (every number finite, speeds not negative, fingertips named) from
  // `now_ns` on. False: the arm refuses it (counted; the arm keeps doing what it did).
  virtual bool write(const wire::ReceivedCommand& command, std::int64_t now_ns) = 0;
  // The peer fell silent past the deadman: stop the wrist and the fingers now, keep the grip.
  virtual void hold(std::int64_t now_ns) = 0;
};

struct ArmServerOptions {
  std::string endpoint = "tcp://*:5556";
  // CURVE: the server's key pair and the client keys let in (docs/security.md).
  std::optional<wire::ServerSecurity> security;
  // Hold the arm when the peer has been silent this long (s): four of hand_node's default
  // heartbeat periods (0.1 s). The rig runs 0.04 s with hand_node heartbeating every 0.01 s.
  double deadman_s = 0.4;
  // A Heartbeat to the peer when nothing was sent to it this long (s); 0: never.
  double heartbeat_period_s = 0.1;
  // The sensor ids of fingertip 0 and 1, as hand_node names them in FingerVelocities.
  wire::FingertipIds fingertip_ids{"left", "right"};
};

struct ArmServerCounters {
  std::uint64_t commands = 0;   // valid commands from the peer, handed to the backend
  std::uint64_t garbage = 0;    // undecodable, of another shape, neither command nor heartbeat
  std::uint64_t strangers = 0;  // another client's heartbeat while the peer is alive
  std::uint64_t invalid_commands = 0;  // decodable but refused: a bad value, or by the backend
  std::uint64_t deadman_trips = 0;
  std::uint64_t states_sent = 0;
  std::uint64_t heartbeats_sent = 0;
  // Every message refused (the rig's log line "commands N (refused M)").
  std::uint64_t refused() const { return garbage + strangers + invalid_commands; }
};

class ArmServer {
 public:
  // Binds the ROUTER (with options.security: a CURVE server that lets in only the authorized
  // clients; it runs the context's authenticator, so one secured ArmServer per context).
  // Throws std::invalid_argument for a deadman or heartbeat period that is not a positive
  // finite number (the heartbeat may be 0), std::runtime_error for an endpoint it cannot bind.
  ArmServer(zmq::context_t& ctx, ArmServerOptions options, ArmBackend& backend);
  ArmServer(const ArmServer&) = delete;
  ArmServer& operator=(const ArmServer&) = delete;

  // Takes one queued message, if any, and handles it at `now_ns`: a heartbeat keeps the peer's
  // deadman, a valid command goes to the backend, anything else is counted. False when nothing
  // was queued.
  bool serve_one(std::int64_t now_ns);
  // Every queued message at `now_ns`, then the deadman and the heartbeat: serve() for a loop that
  // has nothing else to do between polls. Returns the messages handled.
  std::size_t serve(std::int64_t now_ns);
  // Holds the arm (backend.hold) once, when the peer has been silent past the deadman; logs it.
  // Call it at least every few milliseconds: the hold comes at most that late.
  void check_deadman(std::int64_t now_ns);
  // Sends the peer the backend's state (with ARM_FAULT_DEADMAN while held), then checks the
  // deadman. False when there is no peer yet (nothing sent).
  bool send_state(std::int64_t now_ns);
  // Sends the peer a Heartbeat when nothing went to it for heartbeat_period_s.
  void heartbeat_if_quiet(std::int64_t now_ns);

  zmq::socket_ref socket() { return router_.socket(); }
  // The endpoint actually bound (a wildcard port resolved).
  std::string endpoint() const { return router_.endpoint(); }
  const ArmPeer& peer() const { return peer_; }
  // The newest command handed to the backend (its sequence), 0 before any.
  std::uint64_t last_command_sequence() const { return last_command_; }
  ArmServerCounters counters() const;
  // Clients refused by CURVE (their key is not authorized); 0 without security.
  std::uint64_t refused_clients() const { return router_.refused_clients(); }
  const ArmServerOptions& options() const { return options_; }

 private:
  void handle(std::int64_t now_ns);
  void send_envelope(v1::Envelope& env, std::int64_t now_ns);

  ArmServerOptions options_;
  ArmBackend& backend_;
  wire::Router router_;
  ArmPeer peer_;
  ArmServerCounters counters_;
  std::int64_t heartbeat_ns_;
  std::int64_t last_sent_ns_ = 0;
  std::uint64_t last_command_ = 0;
  // Reused buffers: the per-message path allocates nothing once they have grown.
  std::string from_;
  std::vector<std::uint8_t> payload_;
  wire::EnvelopeDecoder decoder_;
  wire::ReceivedCommand command_;
  // One envelope per kind: switching one envelope's oneof would free and allocate its body.
  v1::Envelope state_env_;
  v1::Envelope heartbeat_env_;
  std::string out_;
};

}  // namespace tactile::arm
