#pragma once
/// Small fixed-size vectors for public interfaces. Kept free of Eigen so that users of
/// the public headers compile quickly; the algorithms convert to Eigen internally.

#include <cmath>

namespace isochart {

struct Vec2d {
  double x = 0, y = 0;
  constexpr Vec2d() = default;
  constexpr Vec2d(double x_, double y_) : x(x_), y(y_) {}
  constexpr double operator[](int i) const { return i == 0 ? x : y; }
  double& operator[](int i) { return i == 0 ? x : y; }
  constexpr Vec2d operator+(const Vec2d& o) const { return {x + o.x, y + o.y}; }
  constexpr Vec2d operator-(const Vec2d& o) const { return {x - o.x, y - o.y}; }
  constexpr Vec2d operator-() const { return {-x, -y}; }
  constexpr Vec2d operator*(double s) const { return {x * s, y * s}; }
  constexpr Vec2d operator/(double s) const { return {x / s, y / s}; }
  Vec2d& operator+=(const Vec2d& o) { x += o.x; y += o.y; return *this; }
  Vec2d& operator-=(const Vec2d& o) { x -= o.x; y -= o.y; return *this; }
  Vec2d& operator*=(double s) { x *= s; y *= s; return *this; }
  Vec2d& operator/=(double s) { x /= s; y /= s; return *this; }
  constexpr bool operator==(const Vec2d& o) const { return x == o.x && y == o.y; }
  constexpr bool operator!=(const Vec2d& o) const { return !(*this == o); }
};

struct Vec3d {
  double x = 0, y = 0, z = 0;
  constexpr Vec3d() = default;
  constexpr Vec3d(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
  constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3d operator+(const Vec3d& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3d operator-(const Vec3d& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3d operator-() const { return {-x, -y, -z}; }
  constexpr Vec3d operator*(double s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3d operator/(double s) const { return {x / s, y / s, z / s}; }
  Vec3d& operator+=(const Vec3d& o) { x += o.x; y += o.y; z += o.z; return *this; }
  Vec3d& operator-=(const Vec3d& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  Vec3d& operator*=(double s) { x *= s; y *= s; z *= s; return *this; }
  Vec3d& operator/=(double s) { x /= s; y /= s; z /= s; return *this; }
  constexpr bool operator==(const Vec3d& o) const { return x == o.x && y == o.y && z == o.z; }
  constexpr bool operator!=(const Vec3d& o) const { return !(*this == o); }
};

constexpr Vec2d operator*(double s, const Vec2d& v) { return v * s; }
constexpr Vec3d operator*(double s, const Vec3d& v) { return v * s; }

constexpr double dot(const Vec2d& a, const Vec2d& b) { return a.x * b.x + a.y * b.y; }
constexpr double dot(const Vec3d& a, const Vec3d& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
/// z-component of the 3D cross product: twice the signed area of (0, a, b).
constexpr double cross(const Vec2d& a, const Vec2d& b) { return a.x * b.y - a.y * b.x; }
constexpr Vec3d cross(const Vec3d& a, const Vec3d& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(const Vec2d& a) { return std::sqrt(dot(a, a)); }
inline double norm(const Vec3d& a) { return std::sqrt(dot(a, a)); }
constexpr double squared_norm(const Vec2d& a) { return dot(a, a); }
constexpr double squared_norm(const Vec3d& a) { return dot(a, a); }
inline Vec3d normalized(const Vec3d& a) {
  const double n = norm(a);
  return n > 0 ? a / n : Vec3d{};
}
inline Vec2d normalized(const Vec2d& a) {
  const double n = norm(a);
  return n > 0 ? a / n : Vec2d{};
}
inline bool is_finite(const Vec3d& a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
inline bool is_finite(const Vec2d& a) { return std::isfinite(a.x) && std::isfinite(a.y); }

/// Signed area of the 2D triangle (a, b, c); positive when counter-clockwise.
constexpr double signed_area(const Vec2d& a, const Vec2d& b, const Vec2d& c) {
  return 0.5 * cross(b - a, c - a);
}
/// Area of the 3D triangle (a, b, c).
inline double triangle_area(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return 0.5 * norm(cross(b - a, c - a));
}

}  // namespace isochart
