// HDF5 volume and table reading. libhdf5 itself is not instrumented; a crash
// inside it is still a finding (we then validate more before calling it).
//
// Speed: every H5Fopen callocs the metadata-cache struct (H5C_t, ~0.5 MB).
// libhdf5's free lists keep at most 64 KB per list by default, so that block
// went back to ASan on every close, and ASan serves blocks that large by
// mmap + page faults + munmap (a TLB shootdown in this VM): 70 % of a run's
// time (perf, 2026-11-23). Raising the free-list limits lets libhdf5 reuse
// the block; the reader code path is the CLI's, unchanged.
#include <hdf5.h>

#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  tg::fuzz::limit_memory();
  H5set_free_list_limits(64 << 20, 16 << 20, 64 << 20, 16 << 20, 64 << 20, 16 << 20);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string file = tg::fuzz::scratch("in.h5");
  tg::fuzz::write_file(file, data, size);
  const tg::ReadOptions ro = tg::fuzz::volume_read_options();
  tg::fuzz::expect_clean([&] { tg::read_volume(file, ro); });
  tg::fuzz::expect_clean([&] {
    tg::H5Reader r(file);
    for (const auto& d : r.datasets()) (void)d;
    if (r.has("/particles")) r.read_table("/particles");
  });
  return 0;
}
