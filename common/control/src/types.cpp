#include "tactile/control/types.hpp"

namespace tactile::control {

const char* to_string(CommandKind k) {
  switch (k) {
    case CommandKind::kNone:
      return "NONE";
    case CommandKind::kMoveTo:
      return "MOVE_TO";
    case CommandKind::kFingerVelocities:
      return "FINGER_VELOCITIES";
    case CommandKind::kHold:
      return "HOLD";
    case CommandKind::kOpen:
      return "OPEN";
    case CommandKind::kStop:
      return "STOP";
  }
  return "?";
}

const char* to_string(Phase p) {
  switch (p) {
    case Phase::kIdle:
      return "IDLE";
    case Phase::kApproach:
      return "APPROACH";
    case Phase::kDescend:
      return "DESCEND";
    case Phase::kGrasp:
      return "GRASP";
    case Phase::kLift:
      return "LIFT";
    case Phase::kTransport:
      return "TRANSPORT";
    case Phase::kLower:
      return "LOWER";
    case Phase::kRelease:
      return "RELEASE";
    case Phase::kRetract:
      return "RETRACT";
    case Phase::kTwistApproach:
      return "TWIST_APPROACH";
    case Phase::kTwistGrasp:
      return "TWIST_GRASP";
    case Phase::kTwistTurn:
      return "TWIST_TURN";
    case Phase::kTwistRelease:
      return "TWIST_RELEASE";
    case Phase::kTwistReturn:
      return "TWIST_RETURN";
    case Phase::kTwistFinish:
      return "TWIST_FINISH";
    case Phase::kDone:
      return "DONE";
    case Phase::kAborted:
      return "ABORTED";
  }
  return "?";
}

bool is_twist_phase(Phase p) {
  switch (p) {
    case Phase::kTwistApproach:
    case Phase::kTwistGrasp:
    case Phase::kTwistTurn:
    case Phase::kTwistRelease:
    case Phase::kTwistReturn:
    case Phase::kTwistFinish:
      return true;
    default:
      return false;
  }
}

const char* to_string(FingerMode m) {
  switch (m) {
    case FingerMode::kOff:
      return "OFF";
    case FingerMode::kSearch:
      return "SEARCH";
    case FingerMode::kMove:
      return "MOVE";
  }
  return "?";
}

const char* to_string(EventKind k) {
  switch (k) {
    case EventKind::kPhase:
      return "PHASE";
    case EventKind::kTouch:
      return "TOUCH";
    case EventKind::kGraspingEnded:
      return "GRASPING_ENDED";
    case EventKind::kGraspClassified:
      return "GRASP_CLASSIFIED";
    case EventKind::kReleaseClassified:
      return "RELEASE_CLASSIFIED";
    case EventKind::kRecompress:
      return "RECOMPRESS";
    case EventKind::kOver:
      return "OVER";
    case EventKind::kTwistCycle:
      return "TWIST_CYCLE";
    case EventKind::kCapTight:
      return "CAP_TIGHT";
    case EventKind::kStaleHold:
      return "STALE_HOLD";
    case EventKind::kResumed:
      return "RESUMED";
    case EventKind::kDone:
      return "DONE";
    case EventKind::kAborted:
      return "ABORTED";
  }
  return "?";
}

}  // namespace tactile::control
