// The element types a volume file may hold, and a volume of any of them.
#pragma once
#include <cstdint>
#include <string>
#include <variant>

#include "core/volume.hpp"

namespace tg {

enum class DType { u8, u16, u32, f32 };

inline const char* dtype_name(DType t) {
  switch (t) {
    case DType::u8: return "uint8";
    case DType::u16: return "uint16";
    case DType::u32: return "uint32";
    case DType::f32: return "float32";
  }
  return "?";
}
inline int dtype_bytes(DType t) { return t == DType::u8 ? 1 : t == DType::u16 ? 2 : 4; }

// Parses "uint8|u8|uint16|u16|uint32|u32|float32|f32|float"; throws UsageError.
DType parse_dtype(const std::string& s);

template <class T> constexpr DType dtype_of();
template <> constexpr DType dtype_of<uint8_t>() { return DType::u8; }
template <> constexpr DType dtype_of<uint16_t>() { return DType::u16; }
template <> constexpr DType dtype_of<uint32_t>() { return DType::u32; }
template <> constexpr DType dtype_of<float>() { return DType::f32; }

// A volume of one of the file element types; std::visit dispatches once per
// volume, never per voxel.
using AnyVolume = std::variant<Volume<uint8_t>, Volume<uint16_t>, Volume<uint32_t>, Volume<float>>;

inline DType dtype_of(const AnyVolume& v) {
  return std::visit([](const auto& vol) { return dtype_of<typename std::decay_t<decltype(vol)>::value_type>(); }, v);
}
inline const Shape& shape_of(const AnyVolume& v) {
  return std::visit([](const auto& vol) -> const Shape& { return vol.shape(); }, v);
}
inline const Geometry& geometry_of(const AnyVolume& v) {
  return std::visit([](const auto& vol) -> const Geometry& { return vol.geometry(); }, v);
}
inline void set_geometry(AnyVolume& v, const Geometry& g) {
  std::visit([&](auto& vol) { vol.set_geometry(g); }, v);
}
// Allocates an uninitialised volume of the given type.
AnyVolume make_volume(DType t, Shape s, Geometry g = {});

}  // namespace tg
