#include "core/dtype.hpp"

namespace tg {

DType parse_dtype(const std::string& s) {
  if (s == "uint8" || s == "u8") return DType::u8;
  if (s == "uint16" || s == "u16") return DType::u16;
  if (s == "uint32" || s == "u32") return DType::u32;
  if (s == "float32" || s == "f32" || s == "float") return DType::f32;
  throw UsageError("unknown element type '" + s + "' (valid: uint8, uint16, uint32, float32)");
}

AnyVolume make_volume(DType t, Shape s, Geometry g) {
  switch (t) {
    case DType::u8: return Volume<uint8_t>(s, g);
    case DType::u16: return Volume<uint16_t>(s, g);
    case DType::u32: return Volume<uint32_t>(s, g);
    case DType::f32: return Volume<float>(s, g);
  }
  throw UsageError("unknown element type");
}

}  // namespace tg
