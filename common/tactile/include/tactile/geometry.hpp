#pragma once

#include <array>
#include <cmath>
#include <cstddef>

namespace tactile {

struct Vec2 {
  double x = 0.0;
  double y = 0.0;
};

struct Vec3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
};

inline Vec3 operator+(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3 operator-(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3 operator*(double s, Vec3 a) {
  return {s * a.x, s * a.y, s * a.z};
}
inline double dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline double norm(Vec3 a) {
  return std::sqrt(dot(a, a));
}
inline bool is_finite(Vec3 a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

inline Vec2 operator+(Vec2 a, Vec2 b) {
  return {a.x + b.x, a.y + b.y};
}
inline Vec2 operator-(Vec2 a, Vec2 b) {
  return {a.x - b.x, a.y - b.y};
}
inline Vec2 operator*(double s, Vec2 a) {
  return {s * a.x, s * a.y};
}
inline double norm(Vec2 a) {
  return std::hypot(a.x, a.y);
}

// The axes of each fingertip's frame in the wrist frame (docs/protocol.md, "Frames of
// reference"): fingertip 0 (left) sits at -x_w and squeezes toward +x_w, fingertip 1 (right) the
// other way; y_f points down, z_f is the squeeze direction, x_f = y_f x z_f.
struct FingertipAxes {
  Vec3 x, y, z;
};
inline constexpr std::array<FingertipAxes, 2> kFingertipAxesInWrist{{
    {{0, -1, 0}, {0, 0, -1}, {1, 0, 0}},  // left
    {{0, 1, 0}, {0, 0, -1}, {-1, 0, 0}},  // right
}};
// A vector given in fingertip `axes`' frame, in the wrist frame.
inline Vec3 in_wrist(const FingertipAxes& axes, Vec3 v_f) {
  return v_f.x * axes.x + v_f.y * axes.y + v_f.z * axes.z;
}

}  // namespace tactile
