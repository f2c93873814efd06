// tomograin convert IN -o OUT [--to TYPE] [--range auto|LO,HI]
#include <fmt/core.h>

#include <cmath>
#include <limits>

#include "apps/command.hpp"
#include "core/io/volume_io.hpp"
#include "segmentation/normalise.hpp"

namespace cmd_convert {

struct Opts {
  std::string in, out, to, range = "auto";
  double voxel_um = 0;
  int compression = 0;
};

// Any volume -> u16. float: the study's linear normalisation of [lo, hi] to
// [0, 65535]; integers: values above 65535 are refused, not wrapped.
tg::Volume<uint16_t> to_u16(tg::AnyVolume&& v, const Opts& o) {
  if (auto* f = std::get_if<tg::Volume<float>>(&v)) {
    tg::NormaliseRange r;
    if (o.range == "auto") {
      r = tg::auto_range(*f);
    } else {
      const auto comma = o.range.find(',');
      char* e1 = nullptr;
      char* e2 = nullptr;
      const std::string a = o.range.substr(0, comma), b = comma == std::string::npos ? "" : o.range.substr(comma + 1);
      r.lo = std::strtod(a.c_str(), &e1);
      r.hi = std::strtod(b.c_str(), &e2);
      if (comma == std::string::npos || e1 == a.c_str() || *e1 || e2 == b.c_str() || *e2 || !(r.lo < r.hi))
        throw tg::UsageError("--range must be 'auto' or 'LO,HI' with LO < HI, got '" + o.range + "'");
      r.how = "given range";
    }
    fmt::print("normalising float32 -> uint16: [{:.6g}, {:.6g}] -> [0, 65535] ({})\n", r.lo, r.hi, r.how);
    return tg::normalise_to_u16(*f, r);
  }
  return std::visit(
      [&](auto& vol) -> tg::Volume<uint16_t> {
        using T = typename std::decay_t<decltype(vol)>::value_type;
        if constexpr (std::is_same_v<T, uint16_t>) {
          return std::move(vol);
        } else {
          if (o.range != "auto") throw tg::UsageError("--range applies to float32 input only");
          tg::Volume<uint16_t> out(vol.shape(), vol.geometry());
          for (int64_t i = 0; i < vol.size(); ++i) {
            if constexpr (sizeof(T) > 2)
              if (vol[i] > 65535)
                throw tg::InputError(o.in + ": value " + std::to_string(static_cast<double>(vol[i])) +
                                     " does not fit in uint16");
            out[i] = static_cast<uint16_t>(vol[i]);
          }
          return out;
        }
      },
      v);
}

tg::AnyVolume convert_type(tg::AnyVolume&& v, tg::DType to, const Opts& o) {
  if (tg::dtype_of(v) == to) return std::move(v);
  if (to == tg::DType::u16) return to_u16(std::move(v), o);
  if (to == tg::DType::f32) {
    return std::visit(
        [](auto& vol) -> tg::AnyVolume {
          tg::Volume<float> out(vol.shape(), vol.geometry());
          for (int64_t i = 0; i < vol.size(); ++i) out[i] = static_cast<float>(vol[i]);
          return out;
        },
        v);
  }
  throw tg::UsageError(std::string("conversion to ") + tg::dtype_name(to) +
                       " is not supported (use --to uint16 or --to float32)");
}

int run_convert(const Opts& o) {
  tg::ReadOptions ro;
  ro.voxel_um = o.voxel_um;
  tg::AnyVolume v = tg::read_volume(o.in, ro);
  if (!o.to.empty()) v = convert_type(std::move(v), tg::parse_dtype(o.to), o);
  else if (o.range != "auto") throw tg::UsageError("--range needs --to uint16");
  tg::WriteOptions wo;
  wo.compression = o.compression;
  tg::write_volume(v, o.out, wo);
  const auto s = tg::shape_of(v);
  fmt::print("wrote {} ({} x {} x {} {})\n", o.out, s.nz, s.ny, s.nx, tg::dtype_name(tg::dtype_of(v)));
  return 0;
}

}  // namespace cmd_convert

namespace cmd_convert {
static tg::app::Registrar reg{{"convert", 20,
      "Convert a volume between formats (TIFF file, TIFF slice folder, raw+JSON, HDF5) and,\n"
      "with --to, between element types. Float reconstructions become 16-bit by the study's\n"
      "linear normalisation: [LO, HI] -> [0, 65535], clipped; --range auto uses the 0.01 % and\n"
      "99.99 % percentiles of the grey values (printed). The output format follows its name;\n"
      "a name without extension or ending in '/' is a folder of slices. Output is written\n"
      "atomically: an error leaves nothing behind.\n\n"
      "Examples:\n"
      "  tomograin convert slices/ -o scan.h5 --voxel-um 12.3\n"
      "  tomograin convert recon.tif -o scan.h5 --to uint16 --range auto\n"
      "  tomograin convert recon.h5:/volume -o scan16.tif --to uint16 --range -0.2,1.5\n"
      "  tomograin convert scan.h5 -o scan.json          (raw + JSON sidecar)",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<Opts>();
  sub->add_option("input", o->in, "Input volume (.tif/.tiff, folder, .json sidecar, .h5[:/dataset])")->required();
  sub->add_option("-o,--output", o->out, "Output volume; format from the name")->required();
  sub->add_option("--to", o->to, "Element type of the output: uint16 or float32 (default: keep)");
  sub->add_option("--range", o->range, "float32 -> uint16 grey range: auto (0.01/99.99 % percentiles) or LO,HI")
      ->capture_default_str();
  sub->add_option("--compress", o->compression, "HDF5 deflate level 0-9 (0 = none)")
      ->check(CLI::Range(0, 9))
      ->capture_default_str();
  tg::app::add_voxel_option(sub, o->voxel_um);
  return [o] { return run_convert(*o); };
}}};
}  // namespace cmd_convert
