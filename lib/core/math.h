// Vector math on GLM in double precision, constants and numerically safe helpers.
// Path math (pdfs, Jacobians, differentials, MH ratios) is done in double throughout
// (ARCHITECTURE.md, "Numbers"); no -ffast-math.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include <glm/glm.hpp>

namespace tb {

using Vec2 = glm::dvec2;
using Vec3 = glm::dvec3;
using Vec4 = glm::dvec4;
using Mat3 = glm::dmat3;

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kInvPi = 0.31830988618379067154;
inline constexpr double kInv2Pi = 0.15915494309189533577;
inline constexpr double kInv4Pi = 0.07957747154594766788;
inline constexpr double kPiOver2 = 1.57079632679489661923;
inline constexpr double kPiOver4 = 0.78539816339744830962;
inline constexpr double kSqrt2 = 1.41421356237309504880;
inline constexpr double kEpsilon = std::numeric_limits<double>::epsilon() * 0.5;  // unit roundoff
inline constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Largest double strictly below one: uniforms live in [0, kOneMinusEpsilon].
inline constexpr double kOneMinusEpsilon = 0x1.fffffffffffffp-1;

template <class T> constexpr T sqr(T x) { return x * x; }

// sqrt/acos/asin that clamp arguments pushed just outside their domain by round-off.
inline double safe_sqrt(double x) { return std::sqrt(std::max(0.0, x)); }
inline double safe_acos(double x) { return std::acos(std::clamp(x, -1.0, 1.0)); }
inline double safe_asin(double x) { return std::asin(std::clamp(x, -1.0, 1.0)); }

// a*b - c*d with one rounding error's worth of accuracy (Kahan's algorithm with FMA).
inline double difference_of_products(double a, double b, double c, double d) {
  const double cd = c * d;
  const double err = std::fma(-c, d, cd);
  const double dop = std::fma(a, b, -cd);
  return dop + err;
}
// a*b + c*d, same accuracy.
inline double sum_of_products(double a, double b, double c, double d) {
  const double cd = c * d;
  const double err = std::fma(c, d, -cd);
  const double sop = std::fma(a, b, cd);
  return sop + err;
}

// |v| componentwise and the largest component, without branches: glm::abs compiles to a compare
// and a jump per component, and std::max({...}) to a loop of jumps; for coordinates of random sign
// these were mispredicted about half the time in the path tracer's inner loop (std::abs is a mask,
// nested std::max a maxsd). Same values (the sign of a zero aside).
inline Vec3 abs_components(const Vec3& v) { return {std::abs(v.x), std::abs(v.y), std::abs(v.z)}; }
inline double max_component(const Vec3& v) { return std::max(std::max(v.x, v.y), v.z); }

// c ? a : b by bit masks: GCC turns a ternary on doubles into a jump, which for a random c (the
// wedge of the concentric disk map) is mispredicted half the time.
inline double select_bits(bool c, double a, double b) {
  const uint64_t m = 0 - static_cast<uint64_t>(c);
  return std::bit_cast<double>((std::bit_cast<uint64_t>(a) & m) | (std::bit_cast<uint64_t>(b) & ~m));
}

inline bool is_finite(double x) { return std::isfinite(x); }
inline bool is_finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
inline bool is_finite(const Vec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }

// Compensated (Kahan-Babuska-Neumaier) summation: error independent of the number of terms.
class CompensatedSum {
 public:
  CompensatedSum& operator+=(double x) {
    const double t = sum_ + x;
    if (std::abs(sum_) >= std::abs(x))
      c_ += (sum_ - t) + x;
    else
      c_ += (x - t) + sum_;
    sum_ = t;
    return *this;
  }
  CompensatedSum& operator+=(const CompensatedSum& o) {
    *this += o.sum_;
    *this += o.c_;
    return *this;
  }
  double value() const { return sum_ + c_; }

 private:
  double sum_ = 0.0;
  double c_ = 0.0;
};

}  // namespace tb
