// Strict TOML configs: parse, read typed keys, reject unknown ones.
#include "core/config.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string file = tg::fuzz::scratch("in.toml");
  tg::fuzz::write_file(file, data, size);
  tg::fuzz::expect_clean([&] {
    tg::Config c = tg::Config::from_file(file);
    c.get("material.shear_modulus_Pa", 2.2e9);
    c.get("scene.steps", int64_t{10});
    c.get("scene.name", "oedometer");
    c.get("scene.breakage", true);
    c.get("scene.strains", std::vector<double>{0.0, 0.044});
    c.finish();
  });
  return 0;
}
