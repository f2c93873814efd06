// Raw + JSON sidecar: the input is split at the first NUL byte into the
// sidecar text and the raw data.
#include <cstring>

#include "core/io/volume_io.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  tg::fuzz::limit_memory();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto* nul = static_cast<const uint8_t*>(std::memchr(data, 0, size));
  const size_t json_len = nul ? static_cast<size_t>(nul - data) : size;
  const std::string json = tg::fuzz::scratch("in.json"), raw = tg::fuzz::scratch("in.raw");
  tg::fuzz::write_file(json, data, json_len);
  tg::fuzz::write_file(raw, nul ? nul + 1 : data + size, nul ? size - json_len - 1 : 0);
  tg::ReadOptions ro;
  ro.progress = false;
  tg::fuzz::expect_clean([&] { tg::read_volume(json, ro); });
  return 0;
}
