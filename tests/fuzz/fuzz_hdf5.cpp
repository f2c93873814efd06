// HDF5 volume and table reading. libhdf5 itself is not instrumented; a crash
// inside it is still a finding (we then validate more before calling it).
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  tg::fuzz::limit_memory();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string file = tg::fuzz::scratch("in.h5");
  tg::fuzz::write_file(file, data, size);
  tg::ReadOptions ro;
  ro.progress = false;
  ro.nonfinite = tg::NonFinite::allow;
  tg::fuzz::expect_clean([&] { tg::read_volume(file, ro); });
  tg::fuzz::expect_clean([&] {
    tg::H5Reader r(file);
    for (const auto& d : r.datasets()) (void)d;
    if (r.has("/particles")) r.read_table("/particles");
  });
  return 0;
}
