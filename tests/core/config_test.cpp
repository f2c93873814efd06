#include "core/config.hpp"

#include <gtest/gtest.h>

#include "core/errors.hpp"

namespace tg {

TEST(Config, DefaultsAndValues) {
  Config c = Config::from_string("[material]\nshear_modulus_Pa = 2.2e9\npoisson = 0.25\nsteps = 10\n", "c.toml");
  EXPECT_EQ(c.get("material.shear_modulus_Pa", 1.0), 2.2e9);
  EXPECT_EQ(c.get("material.poisson", 0.0), 0.25);
  EXPECT_EQ(c.get("material.steps", int64_t{1}), 10);
  EXPECT_EQ(c.get("material.density_kg_m3", 2180.0), 2180.0);
  EXPECT_NO_THROW(c.finish());
}

TEST(Config, UnknownKeyIsAnError) {
  Config c = Config::from_string("[material]\nshear_modulus_Pa = 2.2e9\nshaer = 1\n", "c.toml");
  c.get("material.shear_modulus_Pa", 1.0);
  try {
    c.finish();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "c.toml: unknown key 'material.shaer'");
  }
}

TEST(Config, WrongTypeAndSyntaxErrorsNameTheKey) {
  Config c = Config::from_string("dt = \"fast\"\n", "c.toml");
  try {
    c.get("dt", 1.0);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "c.toml: dt must be a number");
  }
  EXPECT_THROW(Config::from_string("a = = 1\n", "bad.toml"), InputError);
  Config r = Config::from_string("nu = 0.6\n", "c.toml");
  const double nu = r.get("nu", 0.25);
  EXPECT_THROW(r.require(nu < 0.5, "nu", "must be below 0.5"), InputError);
}

TEST(Config, ChoiceReadsOneOfItsWordsAndNamesThemOtherwise) {
  enum class Mode { kA, kB, kC };
  const Config::Choices<Mode> modes{{"alpha", Mode::kA}, {"beta", Mode::kB}, {"gamma", Mode::kC}};
  Config c = Config::from_string("[x]\nmode = \"gamma\"\nbad = \"delta\"\n", "c.toml");
  EXPECT_EQ(c.choice("x.mode", modes), Mode::kC);
  EXPECT_EQ(c.choice("x.absent", modes), Mode::kA);  // the first is the default
  try {
    c.choice("x.bad", modes);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "c.toml: x.bad must be one of \"alpha\", \"beta\", \"gamma\" (got \"delta\")");
  }
  EXPECT_EQ(Config::name_of(modes, Mode::kB), "beta");
  for (const auto& [name, value] : modes) EXPECT_EQ(Config::name_of(modes, value), name);
}

}  // namespace tg
