// A 3-vector for contact maths (no Eigen in the hot loop: a plain aggregate
// keeps the pair kernel inlined). The component type is a double, or a pair
// of doubles (dem/lanes.hpp) when the contact loop computes two contacts at
// once; Vec3 is the double one. Always inlined: the contact kernels,
// compiled for several instruction sets, must not share out-of-line copies
// (dem/contact/kernels.hpp).
#pragma once
#include <cmath>
#include <type_traits>

namespace tg::dem {

template <class T>
struct Vec3T {
  T x{}, y{}, z{};
};
using Vec3 = Vec3T<double>;

template <class T> [[gnu::always_inline]] inline Vec3T<T> operator+(Vec3T<T> a, Vec3T<T> b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <class T> [[gnu::always_inline]] inline Vec3T<T> operator-(Vec3T<T> a, Vec3T<T> b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <class T> [[gnu::always_inline]] inline Vec3T<T> operator-(Vec3T<T> a) { return {-a.x, -a.y, -a.z}; }
// s * a for s of the component type, or a plain double applied to every lane.
template <class T> [[gnu::always_inline]] inline Vec3T<T> operator*(std::type_identity_t<T> s, Vec3T<T> a) { return {s * a.x, s * a.y, s * a.z}; }
template <class T>
  requires(!std::is_same_v<T, double>)
[[gnu::always_inline]] inline Vec3T<T> operator*(double s, Vec3T<T> a) {
  return {s * a.x, s * a.y, s * a.z};
}
template <class T> [[gnu::always_inline]] inline T dot(Vec3T<T> a, Vec3T<T> b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T>
[[gnu::always_inline]] inline Vec3T<T> cross(Vec3T<T> a, Vec3T<T> b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(Vec3 a) { return std::sqrt(dot(a, a)); }

}  // namespace tg::dem
