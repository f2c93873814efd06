// TIFF volumes through libtiff: one multi-page file (one page per z slice) or
// a folder of single-page slices sorted naturally (slice_9 before slice_10).
// Pages: one sample per pixel, 8/16/32-bit unsigned or 32-bit IEEE float,
// striped or tiled, any compression libtiff decodes. Files past 4 GB are
// written as BigTIFF.
//
// Voxel size: ImageJ metadata (ImageDescription "unit=", "spacing=" with
// XResolution/YResolution in pixels per unit) or, failing that, resolution
// tags with ResolutionUnit = centimetre. Our writer stores ImageJ-style
// metadata so Fiji and tifffile read the voxel size back.
#pragma once
#include <string>
#include <vector>

#include "core/dtype.hpp"
#include "core/natural_order.hpp"

namespace tg {

// `slices`: only those pages (slice files) are decoded; the origin moves to
// the first (core/io/volume_io.hpp, ReadOptions::slices).
AnyVolume read_tiff(const std::string& path, bool progress, SliceRange slices = {});
AnyVolume read_tiff_folder(const std::string& dir, bool progress, SliceRange slices = {});
// Pages of a multi-page TIFF (the slices), without decoding them.
int64_t tiff_page_count(const std::string& path);
void write_tiff(const AnyVolume& v, const std::string& path, bool progress);
template <class T>
void write_tiff(const Volume<T>& v, const std::string& path, bool progress);
template <class T>
void write_tiff_folder(const Volume<T>& v, const std::string& dir, bool progress);
void write_tiff_folder(const AnyVolume& v, const std::string& dir, bool progress);

// The TIFF files of a folder in natural order; InputError if there are none.
std::vector<std::string> tiff_slices_in(const std::string& dir);

}  // namespace tg
