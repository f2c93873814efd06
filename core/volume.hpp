// Volume<T>: an owning 3-D array (z, y, x), contiguous in x, with its voxel
// size and origin in metres; VolumeView<T>: a cheap non-owning view of a
// volume, a slab of slices or a sub-box (strided in z and y, contiguous in x).
//
// Volumes are move-only: copying 3.6 GB by accident is a bug, so a copy is
// the explicit clone(). Memory is allocated uninitialised (allocate_large:
// huge-page aligned) after check_allocation(), so an impossible request fails
// with a clear message; use Volume::filled() when a defined value is needed.
//
// See core/shape.hpp for the index and coordinate conventions.
#pragma once
#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <type_traits>

#include "core/memory.hpp"
#include "core/shape.hpp"

namespace tg {

// Where a volume sits in space. voxel_size_m and origin_m are (z, y, x).
// A voxel size of 0 means "unknown" (a file without resolution metadata);
// commands that need physical units ask for --voxel-um then.
struct Geometry {
  std::array<double, 3> voxel_size_m{0.0, 0.0, 0.0};
  std::array<double, 3> origin_m{0.0, 0.0, 0.0};

  bool has_voxel_size() const { return voxel_size_m[0] > 0 && voxel_size_m[1] > 0 && voxel_size_m[2] > 0; }
  bool isotropic() const { return voxel_size_m[0] == voxel_size_m[1] && voxel_size_m[1] == voxel_size_m[2]; }
  static Geometry isotropic_m(double voxel_m) { return Geometry{{voxel_m, voxel_m, voxel_m}, {0, 0, 0}}; }
  friend bool operator==(const Geometry&, const Geometry&) = default;
};

// A sub-box [z0, z0+nz) x [y0, y0+ny) x [x0, x0+nx) of a volume.
struct Box {
  int64_t z0 = 0, y0 = 0, x0 = 0;
  Shape size;
};

// Slices [z0, z0 + nz) of a volume on disk, nz < 0: to the last one. What a
// reader (core/io) reads of a file: a slab of a scan larger than memory, the
// slices of a crop; the slab's origin is moved to slice z0.
struct SliceRange {
  int64_t z0 = 0, nz = -1;
  bool whole() const { return z0 == 0 && nz < 0; }
};

template <class T>
class VolumeView {
 public:
  VolumeView() = default;
  VolumeView(T* data, Shape shape, int64_t stride_z, int64_t stride_y, Geometry geom = {})
      : data_(data), shape_(shape), stride_z_(stride_z), stride_y_(stride_y), geom_(geom) {}

  const Shape& shape() const { return shape_; }
  const Geometry& geometry() const { return geom_; }
  T* data() const { return data_; }
  int64_t stride_z() const { return stride_z_; }
  int64_t stride_y() const { return stride_y_; }
  bool contiguous() const { return stride_y_ == shape_.nx && stride_z_ == shape_.ny * shape_.nx; }

  T& operator()(int64_t k, int64_t j, int64_t i) const { return data_[k * stride_z_ + j * stride_y_ + i]; }
  // Row j of slice k: nx contiguous values.
  std::span<T> row(int64_t k, int64_t j) const {
    return {data_ + k * stride_z_ + j * stride_y_, static_cast<size_t>(shape_.nx)};
  }
  // A sub-box of this view, no copy. The box must lie inside the view.
  VolumeView sub(const Box& b) const {
    if (b.z0 < 0 || b.y0 < 0 || b.x0 < 0 || b.size.nz < 0 || b.size.ny < 0 || b.size.nx < 0 ||
        b.z0 + b.size.nz > shape_.nz || b.y0 + b.size.ny > shape_.ny || b.x0 + b.size.nx > shape_.nx)
      throw UsageError("sub-box outside the volume " + shape_.str());
    Geometry g = geom_;
    g.origin_m[0] += b.z0 * g.voxel_size_m[0];
    g.origin_m[1] += b.y0 * g.voxel_size_m[1];
    g.origin_m[2] += b.x0 * g.voxel_size_m[2];
    return VolumeView(data_ + b.z0 * stride_z_ + b.y0 * stride_y_ + b.x0, b.size, stride_z_, stride_y_, g);
  }
  VolumeView slices(int64_t k0, int64_t n) const { return sub(Box{k0, 0, 0, Shape{n, shape_.ny, shape_.nx}}); }

  // Read-only view of the same data.
  operator VolumeView<const T>() const { return {data_, shape_, stride_z_, stride_y_, geom_}; }

 private:
  T* data_ = nullptr;
  Shape shape_;
  int64_t stride_z_ = 0, stride_y_ = 0;
  Geometry geom_;
};

template <class T>
class Volume {
  static_assert(std::is_arithmetic_v<T>, "Volume holds plain numbers");

 public:
  using value_type = T;

  Volume() = default;
  // Allocates shape.voxels() values, uninitialised.
  explicit Volume(Shape shape, Geometry geom = {}) : shape_(shape), geom_(geom) {
    const int64_t n = shape.voxels();
    int64_t bytes = 0;
    if (__builtin_mul_overflow(n, static_cast<int64_t>(sizeof(T)), &bytes))
      throw ResourceError("volume " + shape.str() + " is too large to address");
    check_allocation(bytes, "volume " + shape.str());
    data_.reset(static_cast<T*>(allocate_large(static_cast<size_t>(bytes))));
  }
  static Volume filled(Shape shape, T value, Geometry geom = {}) {
    Volume v(shape, geom);
    v.fill(value);
    return v;
  }

  Volume(Volume&&) noexcept = default;
  Volume& operator=(Volume&&) noexcept = default;
  Volume(const Volume&) = delete;
  Volume& operator=(const Volume&) = delete;

  Volume clone() const {
    Volume v(shape_, geom_);
    std::copy(begin(), end(), v.begin());
    return v;
  }

  const Shape& shape() const { return shape_; }
  int64_t size() const { return shape_.nz * shape_.ny * shape_.nx; }
  int64_t bytes() const { return size() * static_cast<int64_t>(sizeof(T)); }
  bool empty() const { return size() == 0; }
  const Geometry& geometry() const { return geom_; }
  Geometry& geometry() { return geom_; }
  void set_geometry(const Geometry& g) { geom_ = g; }

  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  T* begin() { return data_.get(); }
  T* end() { return data_.get() + size(); }
  const T* begin() const { return data_.get(); }
  const T* end() const { return data_.get() + size(); }
  std::span<T> span() { return {data_.get(), static_cast<size_t>(size())}; }
  std::span<const T> span() const { return {data_.get(), static_cast<size_t>(size())}; }

  T& operator[](int64_t idx) { return data_[idx]; }
  const T& operator[](int64_t idx) const { return data_[idx]; }
  T& operator()(int64_t k, int64_t j, int64_t i) { return data_[shape_.index(k, j, i)]; }
  const T& operator()(int64_t k, int64_t j, int64_t i) const { return data_[shape_.index(k, j, i)]; }

  void fill(T value) { std::fill(begin(), end(), value); }

  // This volume's storage as a volume of another element type, no larger,
  // and the same shape; this one is left empty. Saves an allocation (and
  // the peak memory of holding both) where one stage's output replaces a
  // spent input: a float map over u32 labels, u8 levels over a float map.
  // Fresh pages cost more than the work on them (see allocate_large). The
  // bytes are as they were: the caller writes the values.
  template <class U>
  Volume<U> reuse_as() && {
    static_assert(sizeof(U) <= sizeof(T) && alignof(U) <= alignof(T), "the new element must fit the old one");
    Volume<U> v;
    v.shape_ = shape_;
    v.geom_ = geom_;
    v.data_.reset(reinterpret_cast<U*>(data_.release()));
    shape_ = Shape{};
    return v;
  }

  // Converts each value with f into a volume of a smaller element type
  // written over this one's storage (taken; no second volume). Forward in
  // rounds [b, r b), r = sizeof(T) / sizeof(U), from b = 1: a round reads
  // elements >= b (bytes >= b sizeof(T)) and writes bytes below
  // r b sizeof(U) = b sizeof(T), over elements already read; within a
  // round, in parallel (the round's reads and writes never overlap).
  template <class U, class F>
  Volume<U> convert_in_place(F f) && {
    static_assert(sizeof(U) < sizeof(T) && sizeof(T) % sizeof(U) == 0, "the new element must be smaller");
    constexpr int64_t r = int64_t(sizeof(T) / sizeof(U));
    const int64_t n = size();
    const T* in = data();
    Volume<U> out = std::move(*this).template reuse_as<U>();
    U* o = out.data();
    if (n > 0) {
      const T first = in[0];
      o[0] = f(first);
    }
    for (int64_t b = 1; b < n; b *= r) {
      const int64_t e = std::min(n, r * b);
      const T* __restrict src = in;
      U* __restrict dst = o;
#pragma omp parallel for schedule(static) if (e - b >= (1 << 16))
      for (int64_t i = b; i < e; ++i) dst[i] = f(src[i]);
    }
    return out;
  }

  VolumeView<T> view() { return {data(), shape_, shape_.slice_voxels(), shape_.nx, geom_}; }
  VolumeView<const T> view() const { return {data(), shape_, shape_.slice_voxels(), shape_.nx, geom_}; }
  VolumeView<T> slice(int64_t k) { return view().slices(k, 1); }
  VolumeView<const T> slice(int64_t k) const { return view().slices(k, 1); }
  VolumeView<T> sub(const Box& b) { return view().sub(b); }
  VolumeView<const T> sub(const Box& b) const { return view().sub(b); }

 private:
  template <class>
  friend class Volume;
  Shape shape_;
  Geometry geom_;
  std::unique_ptr<T[], LargeFree> data_;
};

// Copy a (possibly strided) view into a new owning volume.
template <class T>
Volume<std::remove_const_t<T>> to_volume(const VolumeView<T>& v) {
  Volume<std::remove_const_t<T>> out(v.shape(), v.geometry());
  int64_t o = 0;
  for (int64_t k = 0; k < v.shape().nz; ++k)
    for (int64_t j = 0; j < v.shape().ny; ++j) {
      auto r = v.row(k, j);
      std::copy(r.begin(), r.end(), out.data() + o);
      o += v.shape().nx;
    }
  return out;
}

}  // namespace tg
