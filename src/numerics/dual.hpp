// Forward-mode automatic differentiation in one direction: a dual number v + d e (e^2 = 0)
// carries a value and its derivative with respect to one variable through the arithmetic
// (Griewank & Walther, "Evaluating Derivatives", 2nd ed., ch. 3). The value part is computed by
// the same operations as in double, so it has the same bits; the derivative is exact up to
// rounding. Only what the closed forms use: + - * /, sqrt, abs, comparisons of the values.
// Pure: standard library only.
#pragma once
#include <cmath>
#include <type_traits>

namespace truss::numerics {

struct Dual {
  double v = 0;  // value
  double d = 0;  // derivative
  constexpr Dual() = default;
  constexpr Dual(double value) : v(value) {}  // a constant: derivative 0
  constexpr Dual(double value, double derivative) : v(value), d(derivative) {}
};

constexpr Dual operator-(Dual a) { return {-a.v, -a.d}; }
constexpr Dual operator+(Dual a, Dual b) { return {a.v + b.v, a.d + b.d}; }
constexpr Dual operator-(Dual a, Dual b) { return {a.v - b.v, a.d - b.d}; }
constexpr Dual operator*(Dual a, Dual b) { return {a.v * b.v, a.d * b.v + a.v * b.d}; }
constexpr Dual operator/(Dual a, Dual b) { return {a.v / b.v, (a.d * b.v - a.v * b.d) / (b.v * b.v)}; }
constexpr Dual operator+(Dual a, double b) { return {a.v + b, a.d}; }
constexpr Dual operator+(double a, Dual b) { return {a + b.v, b.d}; }
constexpr Dual operator-(Dual a, double b) { return {a.v - b, a.d}; }
constexpr Dual operator-(double a, Dual b) { return {a - b.v, -b.d}; }
constexpr Dual operator*(Dual a, double b) { return {a.v * b, a.d * b}; }
constexpr Dual operator*(double a, Dual b) { return {a * b.v, a * b.d}; }
constexpr Dual operator/(Dual a, double b) { return {a.v / b, a.d / b}; }
constexpr Dual operator/(double a, Dual b) { return {a / b.v, -a * b.d / (b.v * b.v)}; }
constexpr Dual& operator+=(Dual& a, Dual b) { return a = a + b; }
constexpr Dual& operator-=(Dual& a, Dual b) { return a = a - b; }
constexpr Dual& operator*=(Dual& a, Dual b) { return a = a * b; }

constexpr bool operator<(Dual a, Dual b) { return a.v < b.v; }
constexpr bool operator>(Dual a, Dual b) { return a.v > b.v; }
constexpr bool operator<=(Dual a, Dual b) { return a.v <= b.v; }
constexpr bool operator>=(Dual a, Dual b) { return a.v >= b.v; }

// sqrt(a)' = a' / (2 sqrt(a)); at a = 0 the derivative is infinite unless a' = 0 (then 0).
inline Dual sqrt(Dual a) {
  const double s = std::sqrt(a.v);
  return {s, a.d == 0.0 ? 0.0 : a.d / (2.0 * s)};
}
// |a|' = sign(a) a' (at a = 0 the right derivative, a'); the value is std::abs's (no -0).
inline Dual abs(Dual a) { return {std::abs(a.v), a.v < 0.0 ? -a.d : a.d}; }

// The independent variable of generic code: a dual seeded with its derivative, or the double.
template <class T>
constexpr T make_variable(double value, double derivative) {
  if constexpr (std::is_same_v<T, Dual>) return Dual(value, derivative);
  else return T(value);
}

// The value of a double or a dual (generic code that needs the number itself).
constexpr double value_of(double a) { return a; }
constexpr double value_of(Dual a) { return a.v; }

}  // namespace truss::numerics
