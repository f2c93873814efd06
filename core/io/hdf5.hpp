// HDF5: the native container. A tomograin file holds
//   /volume  u16 or f32 grey values (z, y, x), chunked, optionally deflated
//   /labels  u32 particle labels (0 = void)
//   tables (particles, truth) as groups of 1-D datasets, one per column
// with attributes voxel_size_m and origin_m (3 doubles, z y x) and units on
// every volume (other files' element_size_um, z y x in micrometres, is read
// as the voxel size where voxel_size_m is absent). Several datasets go into one file with H5Writer, which writes
// to a temporary and renames on commit().
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/dtype.hpp"
#include "core/table.hpp"

namespace tg {

class H5Writer {
 public:
  // Overwrites `path` on commit(); nothing is left behind if commit() never runs.
  explicit H5Writer(const std::string& path);
  ~H5Writer();
  template <class T>
  void write_volume(const std::string& dataset, const Volume<T>& v, int compression = 0);
  void write_volume(const std::string& dataset, const AnyVolume& v, int compression = 0);
  // A volume written slab by slab (one larger than memory): create_volume
  // makes the dataset (same layout and attributes as write_volume), then
  // write_slab stores slices [vz0, vz0 + nz) of v as the dataset's slices
  // [z0, z0 + nz), in any order. Slabs that start on a multiple of 16
  // slices fill whole chunks.
  void create_volume(const std::string& dataset, DType type, const Shape& shape, const Geometry& geometry,
                     int compression = 0);
  template <class T>
  void write_slab(const std::string& dataset, int64_t z0, const Volume<T>& v, int64_t vz0, int64_t nz);
  void write_table(const std::string& group, const Table& t);
  // A string attribute on the root group (e.g. provenance JSON).
  void write_attribute(const std::string& name, const std::string& value);
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class H5Reader {
 public:
  explicit H5Reader(const std::string& path);
  ~H5Reader();
  bool has(const std::string& dataset) const;
  std::vector<std::string> datasets() const;  // all dataset paths, for messages and `info`
  // `reuse`: a volume whose storage is read into when it has the dataset's
  // type and shape (taken), e.g. a stage series' spent volume.
  AnyVolume read_volume(const std::string& dataset, bool progress = false, AnyVolume* reuse = nullptr) const;
  // Slices [z0, z0 + nz) of a 3-D dataset (a slab of a volume larger than
  // memory), its origin moved to slice z0. InputError outside the dataset.
  // `reuse` as for read_volume: slab after slab into one buffer.
  AnyVolume read_slab(const std::string& dataset, int64_t z0, int64_t nz, AnyVolume* reuse = nullptr) const;
  // The dataset's shape (z, y, x) without reading it; a 2-D dataset is one slice.
  Shape shape(const std::string& dataset) const;
  int rank(const std::string& dataset) const;  // dimensions of a dataset (InputError if it is none)
  Table read_table(const std::string& group) const;
  std::string read_attribute(const std::string& name) const;  // "" if absent

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tg
