// tomograin convert IN -o OUT [--to TYPE] [--range auto|LO,HI]
#include <fmt/core.h>

#include <cmath>
#include <limits>
#include <vector>

#include "apps/command.hpp"
#include "core/io/volume_io.hpp"
#include "segmentation/normalise.hpp"
#include "segmentation/rings.hpp"

namespace cmd_convert {

struct Opts {
  std::string in, out, to, range = "auto", crop;
  bool rings = false;
  std::vector<double> ring_axis;  // --ring-axis Y,X (empty: the slice's centre)
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

// --crop Z0:Z1,Y0:Y1,X0:X1 (voxels, half-open; an empty bound is the volume's edge) as a box
// inside `s`; UsageError naming the option otherwise.
tg::Box parse_crop(const std::string& text, const tg::Shape& s, const std::string& file) {
  const int64_t n[3] = {s.nz, s.ny, s.nx};
  int64_t lo[3], hi[3];
  size_t at = 0;
  for (int a = 0; a < 3; ++a) {
    const size_t end = a < 2 ? text.find(',', at) : text.size();
    const std::string part = end == std::string::npos ? "" : text.substr(at, end - at);
    const size_t colon = part.find(':');
    auto bound = [&](const std::string& b, int64_t dflt) {
      if (b.empty()) return dflt;
      char* e = nullptr;
      const long long v = std::strtoll(b.c_str(), &e, 10);
      if (*e) throw tg::UsageError("--crop: '" + b + "' is not a voxel index (Z0:Z1,Y0:Y1,X0:X1)");
      return static_cast<int64_t>(v);
    };
    if (end == std::string::npos || colon == std::string::npos)
      throw tg::UsageError("--crop must be Z0:Z1,Y0:Y1,X0:X1 (voxels, half-open), got '" + text + "'");
    lo[a] = bound(part.substr(0, colon), 0);
    hi[a] = bound(part.substr(colon + 1), n[a]);
    if (!(0 <= lo[a] && lo[a] < hi[a] && hi[a] <= n[a]))
      throw tg::UsageError("--crop " + text + ": range " + std::to_string(lo[a]) + ":" + std::to_string(hi[a]) +
                           " is empty or outside " + file + "'s " + s.str());
    at = end + 1;
  }
  return tg::Box{lo[0], lo[1], lo[2], tg::Shape{hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}};
}

// The box of `v` as a volume of its own, its origin moved to the box's corner (a tracker or
// a comparison then places the crop where it was).
tg::AnyVolume crop(tg::AnyVolume&& v, const tg::Box& b) {
  return std::visit(
      [&](auto& vol) -> tg::AnyVolume {
        using T = typename std::decay_t<decltype(vol)>::value_type;
        const auto part = vol.view().sub(b);
        tg::Volume<T> out(b.size, part.geometry());
        for (int64_t k = 0; k < b.size.nz; ++k)
          for (int64_t j = 0; j < b.size.ny; ++j) std::copy_n(part.row(k, j).data(), b.size.nx, &out(k, j, 0));
        return out;
      },
      v);
}

// --rings: ring artefacts removed in place (segmentation/rings.hpp), what
// was found printed.
void remove_rings(tg::AnyVolume& v, const Opts& o) {
  tg::RingOptions ro;
  if (!o.ring_axis.empty()) {
    if (o.ring_axis.size() != 2 || !(o.ring_axis[0] >= 0) || !(o.ring_axis[1] >= 0))
      throw tg::UsageError("--ring-axis takes Y,X (two numbers >= 0, voxels from the slice's corner)");
    ro.centre_y = o.ring_axis[0], ro.centre_x = o.ring_axis[1];
  }
  tg::RingResult r;
  if (auto* u = std::get_if<tg::Volume<uint16_t>>(&v)) r = tg::remove_rings(*u, ro);
  else if (auto* f = std::get_if<tg::Volume<float>>(&v)) r = tg::remove_rings(*f, ro);
  else throw tg::UsageError("--rings works on uint16 or float32 scans (add --to uint16)");
  if (r.rings == 0)
    fmt::print("rings: none found ({} radius bins about ({:.1f}, {:.1f}) voxels; the volume is unchanged)\n", r.bins,
               r.centre_y, r.centre_x);
  else
    fmt::print("rings: {} of {} radius bins about ({:.1f}, {:.1f}) voxels corrected, offsets up to {:.4g} grey levels\n",
               r.rings, r.bins, r.centre_y, r.centre_x, r.max_offset);
}

int run_convert(const Opts& o) {
  tg::ReadOptions ro;
  ro.voxel_um = o.voxel_um;
  tg::AnyVolume v;
  if (o.crop.empty()) {
    v = tg::read_volume(o.in, ro);
  } else {
    // Only the box's slices are read (a crop of a scan larger than memory);
    // rows and columns are cut from them.
    tg::Box box = parse_crop(o.crop, tg::read_volume_info(o.in, ro).shape, o.in);
    ro.slices = {box.z0, box.size.nz};
    v = tg::read_volume(o.in, ro);
    box.z0 = 0;
    if (box.size != tg::shape_of(v)) v = crop(std::move(v), box);
  }
  if (!o.to.empty()) v = convert_type(std::move(v), tg::parse_dtype(o.to), o);
  else if (o.range != "auto") throw tg::UsageError("--range needs --to uint16");
  if (o.rings) remove_rings(v, o);
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
      "a name without extension or ending in '/' is a folder of slices. --crop keeps a box, its\n"
      "origin moved with it; only the box's slices are read (a part of a scan larger than memory).\n"
      "--rings removes ring artefacts (a radius of every slice offset by a detector element's\n"
      "gain): each radius bin's mean grey over all slices against the median of its neighbours,\n"
      "removed where it stands over 8 standard errors out (segmentation/rings.hpp); the axis is\n"
      "the slice's centre unless --ring-axis gives it.\n"
      "Output is written atomically: an error leaves nothing behind.\n\n"
      "Examples:\n"
      "  tomograin convert slices/ -o scan.h5 --voxel-um 12.3\n"
      "  tomograin convert recon.tif -o scan.h5 --to uint16 --range auto\n"
      "  tomograin convert recon.h5:/volume -o scan16.tif --to uint16 --range -0.2,1.5\n"
      "  tomograin convert scan.h5 -o scan.json          (raw + JSON sidecar)\n"
      "  tomograin convert labels.h5 -o top.h5 --crop 0:600,:,:   (slices 0-599, origin kept)\n"
      "  tomograin convert scan.h5 -o scan_norings.h5 --rings",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<Opts>();
  sub->add_option("input", o->in, "Input volume (.tif/.tiff, folder, .json sidecar, .h5[:/dataset])")->required();
  sub->add_option("-o,--output", o->out, "Output volume; format from the name")->required();
  sub->add_option("--to", o->to, "Element type of the output: uint16 or float32 (default: keep)");
  sub->add_option("--crop", o->crop,
                  "Keep the box Z0:Z1,Y0:Y1,X0:X1 (voxels, half-open; an empty bound is the edge, e.g. 10:,:,: "
                  "drops 10 slices); the origin moves with it (HDF5 and raw+JSON keep it: track then sees "
                  "stages cropped differently in one frame)");
  sub->add_option("--range", o->range, "float32 -> uint16 grey range: auto (0.01/99.99 % percentiles) or LO,HI")
      ->capture_default_str();
  sub->add_option("--compress", o->compression, "HDF5 deflate level 0-9 (0 = none)")
      ->check(CLI::Range(0, 9))
      ->capture_default_str();
  sub->add_flag("--rings", o->rings,
                "Remove ring artefacts about the rotation axis (after --to; uint16 or float32)");
  sub->add_option("--ring-axis", o->ring_axis,
                  "The rotation axis for --rings: Y,X in voxels from the slice's corner (default: its centre)")
      ->delimiter(',')
      ->expected(2);
  tg::app::add_voxel_option(sub, o->voxel_um);
  return [o] { return run_convert(*o); };
}}};
}  // namespace cmd_convert
