// TIFF reader: arbitrary bytes as a multi-page file and as a one-slice folder.
#include <filesystem>

#include "core/io/volume_io.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  tg::fuzz::limit_memory();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string file = tg::fuzz::scratch("in.tif");
  tg::fuzz::write_file(file, data, size);
  const tg::ReadOptions ro = tg::fuzz::volume_read_options();
  tg::fuzz::expect_clean([&] { tg::read_volume(file, ro); });
  // The same bytes as the only slice of a folder (slice-folder code path).
  const std::string dir = tg::fuzz::scratch("slices");
  std::filesystem::create_directories(dir);
  tg::fuzz::write_file(dir + "/slice_0.tif", data, size);
  tg::fuzz::expect_clean([&] { tg::read_volume(dir, ro); });
  return 0;
}
