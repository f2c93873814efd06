// Round trips between every format for every element type must be bit-exact;
// bad files must raise InputError naming the file and leave nothing behind.
#include "core/io/volume_io.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <tiffio.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include <sys/wait.h>
#include <unistd.h>

#include "core/atomic_file.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/tiff.hpp"

namespace tg {
namespace fs = std::filesystem;

namespace {

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() / ("tg_io_" + std::to_string(::getpid()) + "_" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string operator/(const std::string& n) const { return (path_ / n).string(); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

template <class T>
Volume<T> random_volume(Shape s, uint64_t seed) {
  Volume<T> v(s, Geometry{{12.3e-6, 11e-6, 10e-6}, {0.5, -1.0, 2.0}});
  std::mt19937_64 rng(seed);
  for (auto& x : v) {
    if constexpr (std::is_floating_point_v<T>) x = static_cast<T>(std::normal_distribution<double>(0, 1e3)(rng));
    else x = static_cast<T>(rng());
  }
  return v;
}

template <class T>
void expect_same(const Volume<T>& a, const AnyVolume& b_any) {
  ASSERT_TRUE(std::holds_alternative<Volume<T>>(b_any)) << "element type changed";
  const auto& b = std::get<Volume<T>>(b_any);
  ASSERT_EQ(a.shape(), b.shape());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), static_cast<size_t>(a.bytes())), 0);
}

bool nothing_but(const fs::path& dir, size_t n) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator())) == n;
}

}  // namespace

template <class T>
class RoundTrip : public ::testing::Test {};
using Types = ::testing::Types<uint8_t, uint16_t, uint32_t, float>;
TYPED_TEST_SUITE(RoundTrip, Types);

TYPED_TEST(RoundTrip, EveryFormatBitExact) {
  TempDir d;
  const auto v = random_volume<TypeParam>(Shape{5, 7, 9}, 42);
  for (const std::string name : {"a.tif", "slices", "a.json", "a.h5", "b.h5:/group/data"}) {
    write_volume(v, d / name);
    ReadOptions ro;
    ro.nonfinite = NonFinite::allow;
    const AnyVolume r = read_volume(d / name, ro);
    expect_same(v, r);
    const Geometry g = geometry_of(r);
    // HDF5 and raw keep the geometry exactly; TIFF keeps the voxel size (float32 resolution tags,
    // ImageJ spacing in text) but has no origin.
    EXPECT_NEAR(g.voxel_size_m[2], 10e-6, 1e-12) << name;
    EXPECT_NEAR(g.voxel_size_m[1], 11e-6, 1e-12) << name;
    EXPECT_NEAR(g.voxel_size_m[0], 12.3e-6, 1e-12) << name;
    if (name.find(".h5") != std::string::npos || name == "a.json") {
      EXPECT_EQ(g, v.geometry()) << name;
    }
  }
}

// ReadOptions::slices: every format reads just the slices asked for, the
// same values as those slices of the whole volume, the origin moved to the
// first; read_volume_info gives shape, type and geometry without the voxels.
TYPED_TEST(RoundTrip, EveryFormatReadsASliceRange) {
  TempDir d;
  const auto v = random_volume<TypeParam>(Shape{9, 5, 6}, 7);
  const double dz = v.geometry().voxel_size_m[0];
  for (const std::string name : {"a.tif", "slices", "a.json", "a.h5", "b.h5:/group/data"}) {
    write_volume(v, d / name);
    ReadOptions ro;
    ro.nonfinite = NonFinite::allow;
    const VolumeInfo info = read_volume_info(d / name, ro);
    EXPECT_EQ(info.shape, v.shape()) << name;
    EXPECT_EQ(info.dtype, dtype_of<TypeParam>()) << name;
    const bool tiff = name.find(".h5") == std::string::npos && name != "a.json";  // no origin in TIFF
    const double z_origin = tiff ? 0.0 : v.geometry().origin_m[0];
    EXPECT_DOUBLE_EQ(info.geometry.origin_m[0], z_origin) << name;
    for (const SliceRange r : {SliceRange{0, 9}, SliceRange{3, 4}, SliceRange{8, 1}, SliceRange{2, -1}}) {
      ro.slices = r;
      const AnyVolume got = read_volume(d / name, ro);
      const int64_t nz = r.nz < 0 ? 9 - r.z0 : r.nz;
      Volume<TypeParam> want(Shape{nz, 5, 6});
      std::copy_n(v.data() + r.z0 * 30, nz * 30, want.data());
      expect_same(want, got);
      EXPECT_NEAR(geometry_of(got).origin_m[0], z_origin + double(r.z0) * dz, 1e-15) << name << " z0 " << r.z0;
    }
    for (const SliceRange bad : {SliceRange{9, 1}, SliceRange{4, 6}, SliceRange{-1, 2}, SliceRange{2, 0}}) {
      ro.slices = bad;
      try {
        (void)read_volume(d / name, ro);
        ADD_FAILURE() << name << ": slices " << bad.z0 << "+" << bad.nz << " read";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("are not within its 9 slices"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(split_dataset_spec(d / name).first), std::string::npos) << e.what();
      }
    }
  }
}

TEST(VolumeIO, HDF5CompressedAndTables) {
  TempDir d;
  const auto v = random_volume<uint16_t>(Shape{20, 30, 40}, 3);
  Table t;
  t.add("id", {1, 2, 3});
  t.add_text("kind", {"grain", "half", "chip"});
  {
    H5Writer w(d / "f.h5");
    w.write_volume("/volume", v, 4);
    w.write_table("/particles", t);
    w.commit();
  }
  {
    // A second volume in the same file rewrites the root geometry attributes.
    H5Writer w(d / "g.h5");
    w.write_volume("/volume", v);
    w.write_volume("/labels", Volume<uint32_t>::filled(Shape{2, 2, 2}, 1, Geometry::isotropic_m(5e-6)));
    w.commit();
    EXPECT_EQ(read_volume_as<uint32_t>(d / "g.h5:/labels").geometry().voxel_size_m[0], 5e-6);
    EXPECT_EQ(read_volume_as<uint16_t>(d / "g.h5:/volume").geometry().voxel_size_m[0], 12.3e-6);
  }
  H5Reader r(d / "f.h5");
  expect_same(v, r.read_volume("/volume"));
  const Table rt = r.read_table("/particles");
  EXPECT_EQ(rt.num("id")[2], 3);
  EXPECT_EQ(rt.text("kind")[1], "half");
  EXPECT_THROW(read_volume(d / "f.h5:/nope"), InputError);
}

// Files written by other tools name their volume as they like (/exchange/data
// of a tomography beamline, /segmentation, ...): the only 3-D dataset of a
// file is read without being named; with two, the error lists them.
TEST(VolumeIO, HDF5OnlyThreeDimensionalDatasetIsTheDefault) {
  TempDir d;
  const auto v = random_volume<uint16_t>(Shape{4, 5, 6}, 7);
  auto write = [&](const std::string& file, const std::vector<std::string>& volumes) {
    const hid_t f = H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    const hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    const hsize_t dims[3] = {4, 5, 6}, angles[1] = {180};
    for (const auto& name : volumes) {
      const hid_t sp = H5Screate_simple(3, dims, nullptr);
      const hid_t ds = H5Dcreate2(f, name.c_str(), H5T_NATIVE_UINT16, sp, lcpl, H5P_DEFAULT, H5P_DEFAULT);
      H5Dwrite(ds, H5T_NATIVE_UINT16, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
      H5Dclose(ds);
      H5Sclose(sp);
    }
    const hid_t sp = H5Screate_simple(1, angles, nullptr);  // a 1-D array beside it is not a volume
    H5Dclose(H5Dcreate2(f, "/exchange/theta", H5T_NATIVE_FLOAT, sp, lcpl, H5P_DEFAULT, H5P_DEFAULT));
    H5Sclose(sp);
    H5Pclose(lcpl);
    H5Fclose(f);
  };
  write(d / "one.h5", {"/exchange/data"});
  expect_same(v, read_volume(d / "one.h5"));
  EXPECT_EQ(read_volume_info(d / "one.h5").shape.nz, 4);
  write(d / "two.h5", {"/exchange/data", "/exchange/dark"});
  try {
    read_volume(d / "two.h5");
    FAIL() << "two 3-D datasets and none named";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/exchange/dark"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("two.h5:/DATASET"), std::string::npos) << e.what();
  }
  expect_same(v, read_volume(d / "two.h5:/exchange/dark"));
}

// Volumes with extra dimensions of 1 (ilastik's (z, y, x, c) export, a
// (t, z, y, x) series of one time point) read as (z, y, x); any other
// extra extent is an error naming the dimensions.
TEST(VolumeIO, HDF5ExtraDimensionsOfOneAroundAVolume) {
  TempDir d;
  const Shape s{5, 6, 7};
  const auto v = random_volume<uint16_t>(s, 3);
  const std::string file = d / "axes.h5";
  const hid_t f = H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  auto put = [&](const char* name, std::vector<hsize_t> dims, hid_t type, bool write = true) {
    const hid_t sp = H5Screate_simple(int(dims.size()), dims.data(), nullptr);
    const hid_t ds = H5Dcreate2(f, name, type, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (write) H5Dwrite(ds, H5T_NATIVE_UINT16, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    H5Dclose(ds);
    H5Sclose(sp);
  };
  put("tzyx", {1, 5, 6, 7}, H5T_NATIVE_UINT16);
  put("zyxc", {5, 6, 7, 1}, H5T_NATIVE_UINT16);
  put("tzyxc_labels", {1, 5, 6, 7, 1}, H5T_STD_I64LE);  // signed integers: labels, read as u32
  put("two_channels", {5, 6, 7, 2}, H5T_NATIVE_UINT16, false);  // its shape is what is read
  H5Fclose(f);
  expect_same(v, read_volume(file + ":/tzyx"));
  expect_same(v, read_volume(file + ":/zyxc"));
  EXPECT_EQ(H5Reader(file).shape("/zyxc"), s);
  const auto labels = std::get<Volume<uint32_t>>(H5Reader(file).read_volume("/tzyxc_labels"));
  for (int64_t i = 0; i < s.voxels(); ++i) ASSERT_EQ(labels.data()[i], uint32_t(v.data()[i])) << i;
  const auto slab = std::get<Volume<uint16_t>>(H5Reader(file).read_slab("/zyxc", 2, 3));
  for (int64_t i = 0; i < slab.size(); ++i) ASSERT_EQ(slab.data()[i], v.data()[2 * s.slice_voxels() + i]) << i;
  try {
    read_volume(file + ":/two_channels");
    FAIL() << "two channels are not one volume";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("(5, 6, 7, 2)"), std::string::npos) << e.what();
  }
}

// Slabs of z written out of order into one dataset, read back whole and as
// slabs (origin moved to the slab's first slice); out-of-range slabs are errors.
TEST(VolumeIO, HDF5SlabsWriteAndRead) {
  TempDir d;
  const auto v = random_volume<uint32_t>(Shape{40, 30, 20}, 5);
  Geometry g = v.geometry();
  g.origin_m = {1e-3, 0, 0};
  {
    H5Writer w(d / "s.h5");
    w.create_volume("/labels", DType::u32, v.shape(), g, 1);
    w.write_slab("/labels", 32, v, 32, 8);
    w.write_slab("/labels", 0, v, 0, 32);
    EXPECT_THROW(w.write_slab("/labels", 35, v, 0, 8), UsageError);
    w.commit();
  }
  H5Reader r(d / "s.h5");
  expect_same(v, r.read_volume("/labels"));
  const auto slab = std::get<Volume<uint32_t>>(r.read_slab("/labels", 17, 9));
  ASSERT_EQ(slab.shape(), (Shape{9, 30, 20}));
  for (int64_t i = 0; i < slab.size(); ++i) ASSERT_EQ(slab[i], v[17 * 600 + i]);
  EXPECT_DOUBLE_EQ(slab.geometry().origin_m[0], 1e-3 + 17 * g.voxel_size_m[0]);
  EXPECT_THROW(r.read_slab("/labels", 35, 6), InputError);
}

// ImageJ saves a stack past 4 GB as one TIFF directory, "images=N" in its
// description and the N pages' pixels one after the other (what tifffile and
// ImageJ read back). Built here byte by byte (small: the layout, not the size,
// is the point): read as N slices, in ranges too; cut short, a clear error.
namespace {
void write_imagej_contiguous(const std::string& path, const Volume<uint16_t>& v, bool big_endian) {
  const uint32_t w = uint32_t(v.shape().nx), h = uint32_t(v.shape().ny), n = uint32_t(v.shape().nz);
  const std::string desc = "ImageJ=1.54f\nimages=" + std::to_string(n) + "\nslices=" + std::to_string(n) +
                           "\nunit=micron\nspacing=12.5\nloop=false\n";
  std::string out;
  auto put = [&](uint64_t x, int bytes) {
    for (int b = 0; b < bytes; ++b) out.push_back(char(big_endian ? (x >> (8 * (bytes - 1 - b))) : (x >> (8 * b))));
  };
  const uint32_t entries = 12, ifd = 8, desc_at = ifd + 2 + entries * 12 + 4;
  const uint32_t res_at = desc_at + uint32_t(desc.size() + 1), data_at = res_at + 16;
  out += big_endian ? "MM" : "II";
  put(42, 2);
  put(ifd, 4);
  put(entries, 2);
  auto entry = [&](uint16_t tag, uint16_t type, uint32_t count, uint32_t value) {
    put(tag, 2), put(type, 2), put(count, 4);
    if (type == 3 && count == 1) put(value, 2), put(0, 2);  // a SHORT sits in the first two bytes
    else put(value, 4);
  };
  entry(256, 4, 1, w);                            // ImageWidth
  entry(257, 4, 1, h);                            // ImageLength
  entry(258, 3, 1, 16);                           // BitsPerSample
  entry(259, 3, 1, 1);                            // Compression: none
  entry(262, 3, 1, 1);                            // Photometric: black is zero
  entry(270, 2, uint32_t(desc.size() + 1), desc_at);  // ImageDescription
  entry(273, 4, 1, data_at);                      // StripOffsets: one strip, page 0
  entry(277, 3, 1, 1);                            // SamplesPerPixel
  entry(278, 4, 1, h);                            // RowsPerStrip
  entry(279, 4, 1, w * h * 2);                    // StripByteCounts: page 0 only
  entry(282, 5, 1, res_at);                       // XResolution: 8/100 pixels per micron
  entry(283, 5, 1, res_at + 8);                   // YResolution
  put(0, 4);                                      // no next directory
  out += desc;
  out.push_back('\0');
  for (int k = 0; k < 2; ++k) put(8, 4), put(100, 4);
  for (const uint16_t x : v) put(x, 2);           // every page, contiguous
  std::ofstream(path, std::ios::binary) << out;
}
}  // namespace

TEST(VolumeIO, ImageJContiguousStackOfOneDirectory) {
  TempDir d;
  const auto v = random_volume<uint16_t>(Shape{6, 9, 11}, 3);
  for (const bool big : {false, true}) {
    const std::string path = d / (big ? "ij_be.tif" : "ij.tif");
    write_imagej_contiguous(path, v, big);
    const AnyVolume r = read_volume(path);
    expect_same(v, r);
    EXPECT_NEAR(geometry_of(r).voxel_size_m[0], 12.5e-6, 1e-12);
    EXPECT_EQ(read_volume_info(path).shape, v.shape());
    ReadOptions ro;
    ro.slices = {2, 3};
    Volume<uint16_t> want(Shape{3, 9, 11});
    std::copy_n(v.data() + 2 * 99, 3 * 99, want.data());
    expect_same(want, read_volume(path, ro));
  }
  // The last page cut short: "truncated", naming the file and the bytes missing.
  fs::copy_file(d / "ij.tif", d / "cut.tif");
  fs::resize_file(d / "cut.tif", fs::file_size(d / "ij.tif") - 50);
  try {
    (void)read_volume(d / "cut.tif");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(d / "cut.tif", 0), 0u) << m;
    EXPECT_NE(m.find("ImageJ metadata announces 6 pages"), std::string::npos) << m;
    EXPECT_NE(m.find("needed for contiguous pages"), std::string::npos) << m;
  }
}

TEST(VolumeIO, NaturalSortOfSlices) {
  EXPECT_TRUE(natural_less("slice_9.tif", "slice_10.tif"));
  EXPECT_FALSE(natural_less("slice_10.tif", "slice_9.tif"));
  EXPECT_TRUE(natural_less("a2b3", "a2b10"));
  EXPECT_TRUE(natural_less("s_01.tif", "s_2.tif"));
  // Folder with unpadded names must read in numeric order.
  TempDir d;
  fs::create_directories(d.path() / "in");
  for (int k = 0; k < 12; ++k) {
    Volume<uint8_t> s = Volume<uint8_t>::filled(Shape{1, 2, 2}, static_cast<uint8_t>(k));
    write_volume(s, (d.path() / "in" / ("slice_" + std::to_string(k) + ".tif")).string());
  }
  const auto r = read_volume_as<uint8_t>((d.path() / "in").string());
  ASSERT_EQ(r.shape().nz, 12);
  for (int k = 0; k < 12; ++k) EXPECT_EQ(r(k, 0, 0), k);
}

TEST(VolumeIO, TruncatedTiffIsAnInputError) {
  TempDir d;
  const auto v = random_volume<uint16_t>(Shape{4, 64, 64}, 1);
  write_volume(v, d / "ok.tif");
  const auto size = fs::file_size(d / "ok.tif");
  fs::copy_file(d / "ok.tif", d / "cut.tif");
  fs::resize_file(d / "cut.tif", size / 2);
  try {
    read_volume(d / "cut.tif");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(d / "cut.tif", 0), 0u) << e.what();
  }
  std::ofstream(d / "junk.tif") << "this is not a tiff";
  EXPECT_THROW(read_volume(d / "junk.tif"), InputError);
}

TEST(VolumeIO, MixedSliceSizesAreAnInputError) {
  TempDir d;
  fs::create_directories(d.path() / "in");
  write_volume(Volume<uint16_t>::filled(Shape{1, 4, 4}, 1), (d.path() / "in" / "s_0.tif").string());
  write_volume(Volume<uint16_t>::filled(Shape{1, 4, 5}, 1), (d.path() / "in" / "s_1.tif").string());
  try {
    read_volume((d.path() / "in").string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mixed slice sizes"), std::string::npos) << e.what();
  }
}

TEST(VolumeIO, RawSidecarWithWrongSizeIsAnInputError) {
  TempDir d;
  write_volume(random_volume<uint16_t>(Shape{2, 3, 4}, 1), d / "v.json");
  std::ofstream(d / "w.json") << R"({"shape_zyx": [2, 3, 5], "dtype": "uint16", "files": {"volume_raw": "v.raw"}})";
  try {
    read_volume(d / "w.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("file has 48 bytes"), std::string::npos) << e.what();
  }
  std::ofstream(d / "x.json") << R"({"shape_zyx": [2, -3, 5]})";
  EXPECT_THROW(read_volume(d / "x.json"), InputError);
  std::ofstream(d / "y.json") << R"({"shape_zyx": [4000000000, 4000000000, 4000000000], "files": {"volume_raw": "v.raw"}})";
  EXPECT_THROW(read_volume(d / "y.json"), std::runtime_error);  // overflow: ResourceError
}

TEST(VolumeIO, BigEndianRaw) {
  TempDir d;
  std::ofstream(d / "b.raw", std::ios::binary).write("\x01\x02\x03\x04", 4);
  std::ofstream(d / "b.json") << R"({"shape_zyx": [1, 1, 2], "dtype": "uint16", "byte_order": "big", "voxel_size_um": 5})";
  const auto v = read_volume_as<uint16_t>(d / "b.json");
  EXPECT_EQ(v[0], 0x0102);
  EXPECT_EQ(v[1], 0x0304);
  EXPECT_DOUBLE_EQ(v.geometry().voxel_size_m[0], 5e-6);
}

TEST(VolumeIO, NonFiniteFloatPolicy) {
  TempDir d;
  Volume<float> v = Volume<float>::filled(Shape{2, 2, 2}, 1.f);
  v(1, 0, 1) = NAN;
  v(1, 1, 1) = INFINITY;
  write_volume(v, d / "nan.h5");
  try {
    read_volume(d / "nan.h5");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 NaN/Inf voxel(s), first at (z,y,x)=(1,0,1)"), std::string::npos)
        << e.what();
  }
  ReadOptions allow;
  allow.nonfinite = NonFinite::allow;
  EXPECT_TRUE(std::isnan(read_volume_as<float>(d / "nan.h5", allow)(1, 0, 1)));
}

TEST(VolumeIO, MissingDatasetAndFilesAreInputErrors) {
  TempDir d;
  write_volume(Volume<uint16_t>::filled(Shape{1, 2, 2}, 1), d / "a.h5");
  EXPECT_THROW(read_volume(d / "a.h5:/labels"), InputError);
  EXPECT_THROW(read_volume(d / "none.tif"), InputError);
  EXPECT_THROW(read_volume_as<uint32_t>(d / "a.h5"), InputError);
  std::ofstream(d / "fake.h5") << "not hdf5";
  EXPECT_THROW(read_volume(d / "fake.h5"), InputError);
}

TEST(VolumeIO, FailedWriteLeavesNothingBehind) {
  TempDir d;
  EXPECT_THROW(write_volume(Volume<uint16_t>(Shape{0, 4, 4}), d / "e.tif"), UsageError);
  EXPECT_THROW(write_volume(Volume<uint16_t>(Shape{0, 4, 4}), d / "e.h5"), UsageError);
  EXPECT_TRUE(nothing_but(d.path(), 0));
  EXPECT_THROW(write_volume(Volume<uint16_t>::filled(Shape{1, 1, 1}, 0), d / "no/such/dir/x.tif"), InputError);
}

TEST(VolumeIO, StaleTemporariesOfKilledProcessesAreRemoved) {
  // A process killed between AtomicPath's temporary and its rename leaves
  // ".NAME.tmp-PID-N" behind; a restarted DEM run clears those of dead PIDs.
  TempDir d;
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ::waitpid(child, nullptr, 0);  // `child` is now a PID of no process
  const auto touch = [&](const std::string& name) { std::ofstream(d / name) << "x"; };
  const std::string dead = ".a.h5.tmp-" + std::to_string(child) + "-3";
  const std::string live = ".b.csv.tmp-" + std::to_string(::getpid()) + "-1";
  touch(dead);
  touch(live);
  touch("c.tmp-" + std::to_string(child) + "-1");  // not hidden: not one of ours
  touch("x.h5");
  fs::create_directory(d / (".s.tmp-" + std::to_string(child) + "-7"));  // a folder output's temporary
  touch(".s.tmp-" + std::to_string(child) + "-7/slice_0000.tif");
  EXPECT_EQ(remove_stale_temporaries(d.path()), 2);
  EXPECT_FALSE(fs::exists(d / dead));
  EXPECT_FALSE(fs::exists(d / (".s.tmp-" + std::to_string(child) + "-7")));
  EXPECT_TRUE(fs::exists(d / live));
  EXPECT_TRUE(fs::exists(d / ("c.tmp-" + std::to_string(child) + "-1")));
  EXPECT_TRUE(fs::exists(d / "x.h5"));
  EXPECT_EQ(remove_stale_temporaries(d.path()), 0);
}

// Label volumes as other tools write them: signed and 64-bit integers (TIFF
// sample format 2, HDF5 int types), uint8/uint16, float32 with integer values.
TEST(VolumeIO, LabelVolumesOfAnyIntegerTypeReadAsUint32) {
  TempDir d;
  const int64_t W = 6, H = 5, Z = 3;
  std::vector<int64_t> lab(Z * H * W);
  for (size_t i = 0; i < lab.size(); ++i) lab[i] = (i % 7 == 0) ? 0 : int64_t(i * 40503 % 4000000000ull);
  auto expect_labels = [&](const Volume<uint32_t>& v, const std::string& what) {
    ASSERT_EQ(v.shape(), (Shape{Z, H, W})) << what;
    for (int64_t i = 0; i < v.size(); ++i) ASSERT_EQ(int64_t(v.data()[i]), lab[size_t(i)]) << what << " voxel " << i;
  };
  // TIFF: int64 and uint64 pages (libtiff directly: our writer writes unsigned types only).
  auto tiff_of = [&](const std::string& name, uint16_t fmt, const std::vector<int64_t>& vals) {
    const std::string p = d / name;
    TIFF* t = TIFFOpen(p.c_str(), "w");
    for (int64_t z = 0; z < Z; ++z) {
      TIFFSetField(t, TIFFTAG_IMAGEWIDTH, uint32_t(W));
      TIFFSetField(t, TIFFTAG_IMAGELENGTH, uint32_t(H));
      TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 64);
      TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, fmt);
      TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
      TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
      TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, uint32_t(H));
      TIFFWriteEncodedStrip(t, 0, const_cast<int64_t*>(vals.data() + z * H * W), tmsize_t(H * W * 8));
      TIFFWriteDirectory(t);
    }
    TIFFClose(t);
    return p;
  };
  expect_labels(read_label_volume(tiff_of("i64.tif", SAMPLEFORMAT_INT, lab)), "int64 TIFF");
  expect_labels(read_label_volume(tiff_of("u64.tif", SAMPLEFORMAT_UINT, lab)), "uint64 TIFF");
  std::vector<int64_t> bad = lab;
  bad[17] = -1;
  try {
    read_label_volume(tiff_of("neg.tif", SAMPLEFORMAT_INT, bad));
    ADD_FAILURE() << "a negative label was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("neg.tif: page 0: value -1 at (y,x)=(2,5) is not a label"), std::string::npos)
        << e.what();
  }
  bad[17] = int64_t(1) << 33;
  EXPECT_THROW(read_label_volume(tiff_of("big.tif", SAMPLEFORMAT_INT, bad)), InputError);
  // HDF5: int64 and int32 datasets (libhdf5 directly, chunked and deflated as h5py writes them).
  auto h5_of = [&](const std::string& name, hid_t ftype, const std::vector<int64_t>& vals) {
    const std::string p = d / name;
    hid_t f = H5Fcreate(p.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    hsize_t dims[3] = {hsize_t(Z), hsize_t(H), hsize_t(W)}, chunk[3] = {1, hsize_t(H), hsize_t(W)};
    hid_t sp = H5Screate_simple(3, dims, nullptr);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 3, chunk);
    H5Pset_deflate(dcpl, 4);
    hid_t ds = H5Dcreate2(f, "labels", ftype, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    H5Dwrite(ds, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, vals.data());
    H5Dclose(ds);
    H5Pclose(dcpl);
    H5Sclose(sp);
    H5Fclose(f);
    return p;
  };
  expect_labels(read_label_volume(h5_of("i64.h5", H5T_STD_I64LE, lab) + ":/labels"), "int64 HDF5");
  std::vector<int64_t> small = lab;
  for (auto& v : small) v %= 2000000000;
  std::swap(small, lab);
  expect_labels(read_label_volume(h5_of("i32.h5", H5T_STD_I32BE, lab) + ":/labels"), "int32 big-endian HDF5");
  std::swap(small, lab);
  bad = lab;
  bad[3] = -5;
  EXPECT_THROW(read_label_volume(h5_of("neg.h5", H5T_STD_I64LE, bad) + ":/labels"), InputError);
  // uint16 widened; float32 integers read; a float32 grey scan refused.
  Volume<uint16_t> u16(Shape{2, 2, 2});
  for (int64_t i = 0; i < 8; ++i) u16.data()[i] = uint16_t(i * 9000);
  write_volume(u16, d / "u16.tif");
  const Volume<uint32_t> w = read_label_volume(d / "u16.tif");
  for (int64_t i = 0; i < 8; ++i) EXPECT_EQ(w.data()[i], uint32_t(i * 9000));
  Volume<float> f32(Shape{2, 2, 2});
  for (int64_t i = 0; i < 8; ++i) f32.data()[i] = float(i * 1000);
  write_volume(f32, d / "f.h5");
  EXPECT_EQ(read_label_volume(d / "f.h5").data()[7], 7000u);
  f32.data()[5] = 0.5f;
  write_volume(f32, d / "g.h5");
  EXPECT_THROW(read_label_volume(d / "g.h5"), InputError);
}

TEST(VolumeIO, TiledTiffReads) {
  // Tiled pages come from other tools (not our writer): build one with libtiff directly.
  TempDir d;
  const std::string p = d / "tiled.tif";
  TIFF* t = TIFFOpen(p.c_str(), "w");
  const uint32_t W = 40, H = 33;
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, W);
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, H);
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 16);
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(t, TIFFTAG_TILEWIDTH, 16);
  TIFFSetField(t, TIFFTAG_TILELENGTH, 16);
  TIFFSetField(t, TIFFTAG_RESOLUTIONUNIT, RESUNIT_CENTIMETER);
  TIFFSetField(t, TIFFTAG_XRESOLUTION, 1000.f);  // 10 um pixels
  TIFFSetField(t, TIFFTAG_YRESOLUTION, 1000.f);
  std::vector<uint16_t> tile(16 * 16);
  for (uint32_t y0 = 0; y0 < H; y0 += 16)
    for (uint32_t x0 = 0; x0 < W; x0 += 16) {
      for (uint32_t y = 0; y < 16; ++y)
        for (uint32_t x = 0; x < 16; ++x) tile[y * 16 + x] = static_cast<uint16_t>((y0 + y) * 1000 + x0 + x);
      TIFFWriteTile(t, tile.data(), x0, y0, 0, 0);
    }
  TIFFClose(t);
  const auto v = read_volume_as<uint16_t>(p);
  ASSERT_EQ(v.shape(), (Shape{1, H, W}));
  EXPECT_EQ(v(0, 32, 39), 32 * 1000 + 39);
  EXPECT_EQ(v(0, 17, 5), 17 * 1000 + 5);
  EXPECT_NEAR(v.geometry().voxel_size_m[2], 10e-6, 1e-12);
}

// Tiles may be larger than the page (writers with a fixed 256 x 256 tile):
// read. A tile that would need more than 64 MiB and more than the page is a
// corrupt header: refused before its buffer is allocated (fuzzing found a
// 374-byte file asking for 7.3 GB; tests/fuzz/regressions/tiff/).
TEST(VolumeIO, TiledTiffTileLargerThanPage) {
  TempDir d;
  auto write = [&](const std::string& p, uint32_t tile_w, uint32_t tile_h, bool with_data) {
    TIFF* t = TIFFOpen(p.c_str(), "w");
    TIFFSetField(t, TIFFTAG_IMAGEWIDTH, 10u);
    TIFFSetField(t, TIFFTAG_IMAGELENGTH, 3u);
    TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 8);
    TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
    TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
    TIFFSetField(t, TIFFTAG_TILEWIDTH, tile_w);
    TIFFSetField(t, TIFFTAG_TILELENGTH, tile_h);
    if (with_data) {
      std::vector<uint8_t> tile(size_t(tile_w) * tile_h, 0);
      for (uint32_t y = 0; y < 3; ++y)
        for (uint32_t x = 0; x < 10; ++x) tile[y * tile_w + x] = uint8_t(10 * y + x);
      TIFFWriteTile(t, tile.data(), 0, 0, 0, 0);
    } else {
      std::vector<uint8_t> dummy(16, 0);
      TIFFWriteRawTile(t, 0, dummy.data(), dummy.size());  // a short tile: the header is what matters
    }
    TIFFClose(t);
  };
  const std::string ok = d / "tile256.tif";
  write(ok, 256, 256, true);
  const auto v = read_volume_as<uint8_t>(ok);
  ASSERT_EQ(v.shape(), (Shape{1, 3, 10}));
  EXPECT_EQ(v(0, 2, 9), 29);
  const std::string bad = d / "tile_huge.tif";
  write(bad, 16384, 8192, false);  // 128 MiB per tile for a 30-byte page
  try {
    read_volume_as<uint8_t>(bad);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("16384 x 8192 tiles"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("tile_huge.tif"), std::string::npos) << e.what();
  }
}


// h5py's idiom `f["volume"].attrs["voxel_size_m"] = 12.3e-6` stores ONE
// double: read as an isotropic size. Two values are an error, not "no size".
TEST(VolumeIO, HDF5ScalarVoxelSizeIsIsotropic) {
  const auto dir = std::filesystem::temp_directory_path() / ("tg_h5scalar_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  auto make = [&](const std::string& name, int nvalues) {
    const std::string path = (dir / name).string();
    const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    const hsize_t dims[3] = {2, 3, 4};
    const hid_t sp = H5Screate_simple(3, dims, nullptr);
    const hid_t d = H5Dcreate2(f, "volume", H5T_NATIVE_UINT16, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    std::vector<uint16_t> v(24, 7);
    H5Dwrite(d, H5T_NATIVE_UINT16, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    const hsize_t n = static_cast<hsize_t>(nvalues);
    const hid_t asp = nvalues == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr);
    const hid_t a = H5Acreate2(d, "voxel_size_m", H5T_NATIVE_DOUBLE, asp, H5P_DEFAULT, H5P_DEFAULT);
    const double vals[2] = {12.3e-6, 12.3e-6};
    H5Awrite(a, H5T_NATIVE_DOUBLE, vals);
    H5Aclose(a);
    H5Sclose(asp);
    H5Dclose(d);
    H5Sclose(sp);
    H5Fclose(f);
    return path;
  };
  const auto v = read_volume_as<uint16_t>(make("scalar.h5", 1) + ":/volume");
  for (double e : v.geometry().voxel_size_m) EXPECT_EQ(e, 12.3e-6);
  try {
    read_volume(make("two.h5", 2) + ":/volume");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("voxel_size_m holds 2 values"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

// Fiji's HDF5 plugin gives the voxel size as element_size_um
// (z, y, x, micrometres); voxel_size_m wins where both are present.
TEST(VolumeIO, HDF5ElementSizeUmIsTheVoxelSize) {
  TempDir dir;
  auto make = [&](const std::string& name, bool with_si) {
    const std::string path = dir / name;
    const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    const hsize_t dims[3] = {2, 3, 4}, three = 3;
    const hid_t sp = H5Screate_simple(3, dims, nullptr);
    const hid_t d = H5Dcreate2(f, "data", H5T_NATIVE_UINT16, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    std::vector<uint16_t> v(24, 7);
    H5Dwrite(d, H5T_NATIVE_UINT16, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    const hid_t asp = H5Screate_simple(1, &three, nullptr);
    const double um[3] = {24.6, 12.3, 12.3}, m[3] = {5e-6, 5e-6, 5e-6};
    const hid_t a = H5Acreate2(d, "element_size_um", H5T_NATIVE_FLOAT, asp, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, H5T_NATIVE_DOUBLE, um);
    H5Aclose(a);
    if (with_si) {
      const hid_t b = H5Acreate2(d, "voxel_size_m", H5T_NATIVE_DOUBLE, asp, H5P_DEFAULT, H5P_DEFAULT);
      H5Awrite(b, H5T_NATIVE_DOUBLE, m);
      H5Aclose(b);
    }
    H5Sclose(asp);
    H5Dclose(d);
    H5Sclose(sp);
    H5Fclose(f);
    return path;
  };
  const auto g = read_volume_as<uint16_t>(make("fiji.h5", false) + ":/data").geometry();
  EXPECT_NEAR(g.voxel_size_m[0], 24.6e-6, 1e-11);  // stored as float: 24.6 to 7 digits
  EXPECT_NEAR(g.voxel_size_m[1], 12.3e-6, 1e-11);
  EXPECT_NEAR(g.voxel_size_m[2], 12.3e-6, 1e-11);
  const auto both = read_volume_as<uint16_t>(make("both.h5", true) + ":/data").geometry();
  for (double e : both.voxel_size_m) EXPECT_EQ(e, 5e-6);
}

TEST(VolumeIO, IsHdf5DecidesByTheFilePart) {
  EXPECT_TRUE(is_hdf5("a.h5"));
  EXPECT_TRUE(is_hdf5("dir.x/a.HDF5:/volume"));
  EXPECT_TRUE(is_hdf5("scan.nxs:/entry/data"));
  EXPECT_FALSE(is_hdf5("a.h5.csv"));
  EXPECT_FALSE(is_hdf5("stack.tif"));
  EXPECT_FALSE(is_hdf5("folder.h5x/"));
}

// Compressed volumes are (de)compressed chunk by chunk on every core
// (core/io/hdf5_chunks.hpp) in HDF5's own filter format: libhdf5's filter
// path is the independent reference, both ways, with edge chunks in every axis.
namespace {
template <class T>
Volume<T> runs_volume(Shape s, uint64_t seed) {  // label-like: runs of equal values, many zeros
  Volume<T> v(s, Geometry{{12.3e-6, 12.3e-6, 12.3e-6}, {0, 0, 0}});
  std::mt19937_64 rng(seed);
  T cur = 0;
  for (auto& x : v) {
    if (rng() % 23 == 0) cur = rng() % 3 == 0 ? T(0) : static_cast<T>(rng());
    x = cur;
  }
  return v;
}

template <class T>
Volume<T> read_with_libhdf5(const std::string& path, const char* name, Shape s) {
  Volume<T> v(s);
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  const hid_t t = std::is_same_v<T, uint32_t> ? H5T_NATIVE_UINT32 : std::is_same_v<T, uint16_t> ? H5T_NATIVE_UINT16
                                                                                                : H5T_NATIVE_UINT8;
  EXPECT_GE(H5Dread(d, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), 0);
  H5Dclose(d);
  H5Fclose(f);
  return v;
}
}  // namespace

TEST(Hdf5Chunks, ParallelDeflateReadsBackThroughLibhdf5) {
  TempDir dir;
  const Shape s{37, 300, 270};  // 3 chunk rows (16, 16, 5 slices), 2 x 2 chunks per row, edges in y and x
  const auto labels = runs_volume<uint32_t>(s, 3);
  const auto grey = runs_volume<uint16_t>(s, 4);
  const auto mask = runs_volume<uint8_t>(s, 5);
  const auto raw = runs_volume<uint16_t>(s, 6);
  {
    H5Writer w(dir / "c.h5");
    w.write_volume("/labels", labels, 1);
    w.write_volume("/volume", grey, 6);
    w.write_volume("/mask", mask, 1);
    w.write_volume("/raw", raw, 0);  // chunked, no filter: chunks moved whole
    w.commit();
  }
  const auto l2 = read_with_libhdf5<uint32_t>(dir / "c.h5", "/labels", s);
  const auto g2 = read_with_libhdf5<uint16_t>(dir / "c.h5", "/volume", s);
  const auto m2 = read_with_libhdf5<uint8_t>(dir / "c.h5", "/mask", s);
  EXPECT_EQ(std::memcmp(l2.data(), labels.data(), size_t(s.voxels()) * 4), 0);
  EXPECT_EQ(std::memcmp(g2.data(), grey.data(), size_t(s.voxels()) * 2), 0);
  EXPECT_EQ(std::memcmp(m2.data(), mask.data(), size_t(s.voxels())), 0);
  const auto r2 = read_with_libhdf5<uint16_t>(dir / "c.h5", "/raw", s);
  EXPECT_EQ(std::memcmp(r2.data(), raw.data(), size_t(s.voxels()) * 2), 0);
  // And through tomograin's reader (the parallel inflate; the raw chunks).
  const auto back = std::get<Volume<uint32_t>>(H5Reader(dir / "c.h5").read_volume("/labels"));
  EXPECT_EQ(std::memcmp(back.data(), labels.data(), size_t(s.voxels()) * 4), 0);
  const auto rb = std::get<Volume<uint16_t>>(H5Reader(dir / "c.h5").read_volume("/raw"));
  EXPECT_EQ(std::memcmp(rb.data(), raw.data(), size_t(s.voxels()) * 2), 0);
  const auto rs = std::get<Volume<uint16_t>>(H5Reader(dir / "c.h5").read_slab("/raw", 13, 20));  // across chunk rows
  EXPECT_EQ(std::memcmp(rs.data(), raw.data() + 13 * s.slice_voxels(), size_t(20 * s.slice_voxels()) * 2), 0);
}

// Deflated (shuffle + deflate) and unfiltered chunks written by libhdf5.
class Hdf5ChunksFromLibhdf5 : public ::testing::TestWithParam<bool> {};
INSTANTIATE_TEST_SUITE_P(Hdf5Chunks, Hdf5ChunksFromLibhdf5, ::testing::Values(true, false));

// Chunks of 8 x 16 x 32 (not tomograin's), shuffled and deflated or not.
hid_t libhdf5_chunks(bool deflate) {
  const hsize_t chunk[3] = {8, 16, 32};
  const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(dcpl, 3, chunk);
  if (deflate) {
    H5Pset_shuffle(dcpl);
    H5Pset_deflate(dcpl, 4);
  }
  return dcpl;
}

TEST_P(Hdf5ChunksFromLibhdf5, ReadsIncludingUnwrittenChunks) {
  TempDir dir;
  const Shape s{21, 40, 50};
  const auto grey = runs_volume<uint16_t>(s, 8);
  const std::string path = dir / "lib.h5";
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t dims[3] = {21, 40, 50};
  const hid_t sp = H5Screate_simple(3, dims, nullptr);
  const hid_t dcpl = libhdf5_chunks(GetParam());
  const hid_t d = H5Dcreate2(f, "volume", H5T_NATIVE_UINT16, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  // Slices 0..15 only: the chunks of the last row are never written (read as 0).
  const hsize_t start[3] = {0, 0, 0}, count[3] = {16, 40, 50};
  const hid_t fsp = H5Dget_space(d);
  H5Sselect_hyperslab(fsp, H5S_SELECT_SET, start, nullptr, count, nullptr);
  const hid_t msp = H5Screate_simple(3, count, nullptr);
  ASSERT_GE(H5Dwrite(d, H5T_NATIVE_UINT16, msp, fsp, H5P_DEFAULT, grey.data()), 0);
  for (hid_t h : {msp, fsp, sp}) H5Sclose(h);
  H5Pclose(dcpl);
  H5Dclose(d);
  H5Fclose(f);
  const auto back = std::get<Volume<uint16_t>>(H5Reader(path).read_volume("/volume"));
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j)
      for (int64_t i = 0; i < s.nx; ++i) ASSERT_EQ(back(k, j, i), k < 16 ? grey(k, j, i) : 0) << k << " " << j << " " << i;
}

// A big-endian dataset (older beamline files, Java and MATLAB writers):
// its chunks' stored bytes are not this machine's values, so the chunk path
// must not move them as they are (it did: a u16 scan read as noise).
TEST_P(Hdf5ChunksFromLibhdf5, BigEndianDatasetsReadByValue) {
  TempDir dir;
  const Shape s{21, 40, 50};
  const auto grey = runs_volume<uint16_t>(s, 8);
  Volume<float> att(s);
  for (int64_t i = 0; i < s.voxels(); ++i) att.data()[i] = 0.5f + 1e-4f * float(grey.data()[i]);
  const std::string path = dir / "be.h5";
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t dims[3] = {21, 40, 50};
  const hid_t sp = H5Screate_simple(3, dims, nullptr);
  const hid_t dcpl = libhdf5_chunks(GetParam());
  const hid_t du = H5Dcreate2(f, "u16", H5T_STD_U16BE, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  const hid_t df = H5Dcreate2(f, "f32", H5T_IEEE_F32BE, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  ASSERT_GE(H5Dwrite(du, H5T_NATIVE_UINT16, H5S_ALL, H5S_ALL, H5P_DEFAULT, grey.data()), 0);
  ASSERT_GE(H5Dwrite(df, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, att.data()), 0);
  H5Sclose(sp);
  H5Pclose(dcpl);
  H5Dclose(du);
  H5Dclose(df);
  H5Fclose(f);
  const auto bu = std::get<Volume<uint16_t>>(H5Reader(path).read_volume("/u16"));
  EXPECT_EQ(std::memcmp(bu.data(), grey.data(), size_t(s.voxels()) * 2), 0);
  const auto bf = std::get<Volume<float>>(H5Reader(path).read_volume("/f32"));
  EXPECT_EQ(std::memcmp(bf.data(), att.data(), size_t(s.voxels()) * 4), 0);
  const auto slab = std::get<Volume<uint16_t>>(H5Reader(path).read_slab("/u16", 8, 8));  // one whole row of chunks
  EXPECT_EQ(std::memcmp(slab.data(), grey.data() + 8 * s.slice_voxels(), size_t(8 * s.slice_voxels()) * 2), 0);
}

TEST(Hdf5Chunks, AChunkThatDoesNotInflateIsAnInputErrorNamingIt) {
  TempDir dir;
  const Shape s{16, 20, 20};
  {
    H5Writer w(dir / "bad.h5");
    w.write_volume("/labels", runs_volume<uint32_t>(s, 1), 1);
    w.commit();
  }
  const std::string path = dir / "bad.h5";
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  const hid_t d = H5Dopen2(f, "labels", H5P_DEFAULT);
  const hsize_t offset[3] = {0, 0, 0};
  const unsigned char junk[40] = {0x78, 0x01, 0xde, 0xad};  // a zlib header, then nonsense
  ASSERT_GE(H5Dwrite_chunk(d, H5P_DEFAULT, 0, offset, sizeof junk, junk), 0);
  H5Dclose(d);
  H5Fclose(f);
  try {
    H5Reader(path).read_volume("/labels");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.h5:/labels: corrupt chunk at slice 0"), std::string::npos) << e.what();
  }
}

// An output path that names a device must be refused before any work, and
// the device left alone (a folder of slices once replaced /dev/null).
TEST(AtomicOutput, RefusesADeviceAndLeavesItAlone) {
  ASSERT_TRUE(fs::is_character_file("/dev/null"));
  EXPECT_THROW(AtomicPath("/dev/null"), UsageError);
  EXPECT_THROW(write_file_atomic("/dev/null", "x"), UsageError);
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  // A folder output still replaces an earlier one.
  TempDir dir;
  fs::create_directories(dir.path() / "out" / "old");
  {
    AtomicPath out(dir.path() / "out");
    fs::create_directories(out.temp() / "new");
    out.commit();
  }
  EXPECT_TRUE(fs::is_directory(dir.path() / "out" / "new"));
  EXPECT_FALSE(fs::exists(dir.path() / "out" / "old"));
}

TEST(Hdf5Chunks, ReadsIntoTheStorageOfAVolumeOfTheSameTypeAndShape) {
  TempDir dir;
  const Shape s{20, 30, 40};
  const auto labels = runs_volume<uint32_t>(s, 9);
  write_volume(labels, dir / "l.h5", WriteOptions{1, false});
  AnyVolume spare = Volume<uint32_t>::filled(s, 7u);
  const uint32_t* storage = std::get<Volume<uint32_t>>(spare).data();
  ReadOptions ro;
  ro.progress = false;
  ro.reuse = &spare;
  const auto back = read_volume_as<uint32_t>(dir / "l.h5", ro);
  EXPECT_EQ(back.data(), storage);  // taken
  EXPECT_EQ(std::memcmp(back.data(), labels.data(), size_t(s.voxels()) * 4), 0);
  EXPECT_EQ(back.geometry().voxel_size_m, labels.geometry().voxel_size_m);
  AnyVolume other = Volume<uint32_t>::filled(Shape{20, 30, 41}, 7u);  // another shape: not used
  ro.reuse = &other;
  const auto fresh = read_volume_as<uint32_t>(dir / "l.h5", ro);
  EXPECT_NE(fresh.data(), std::get<Volume<uint32_t>>(other).data());
  EXPECT_EQ(std::memcmp(fresh.data(), labels.data(), size_t(s.voxels()) * 4), 0);
}
}  // namespace tg
