#pragma once

// When hand_node starts the task, and when it says again what it is waiting for
// (docs/hand_node.md "The loop"). The task starts once the arm controller has answered and each
// fingertip has sent enough whole frames; until then the wait is reported at once and then every
// report period, so a hand_node left without an arm controller or a camera says so for as long
// as it waits.
//
// Pure: time is an argument, nothing allocates, nothing throws.
#include <array>
#include <cstdint>

namespace tactile::hand {

class TaskStart {
 public:
  struct Check {
    bool start = false;           // start the task now (true once)
    bool report_waiting = false;  // say what it waits for and what it has
  };

  TaskStart(std::uint64_t frames_needed, std::int64_t report_period_ns) noexcept
      : frames_needed_(frames_needed), report_period_ns_(report_period_ns) {}

  // At now_ns, before the task started: arm_heard, an ArmState came; whole_frames, per fingertip.
  Check check(std::int64_t now_ns, bool arm_heard,
              const std::array<std::uint64_t, 2>& whole_frames) noexcept {
    Check c;
    if (started_) return c;
    if (arm_heard && whole_frames[0] >= frames_needed_ && whole_frames[1] >= frames_needed_) {
      started_ = true;
      start_ns_ = now_ns;
      c.start = true;
      return c;
    }
    if (!reported_ || now_ns - last_report_ns_ >= report_period_ns_) {
      reported_ = true;
      last_report_ns_ = now_ns;
      c.report_waiting = true;
    }
    return c;
  }

  bool started() const noexcept { return started_; }
  // The task's time zero (the controller's now_s counts from it).
  std::int64_t start_ns() const noexcept { return start_ns_; }

 private:
  std::uint64_t frames_needed_;
  std::int64_t report_period_ns_;
  bool started_ = false;
  std::int64_t start_ns_ = 0;
  bool reported_ = false;
  std::int64_t last_report_ns_ = 0;
};

}  // namespace tactile::hand
