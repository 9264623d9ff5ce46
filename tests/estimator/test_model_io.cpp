#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "estimator/model_io.hpp"
#include "estimator/simulate.hpp"

namespace tsmh::estimator {
namespace {

std::string error_of(const std::string& yaml) {
  try {
    parse_model(yaml, "p.yaml");
  } catch (const ParamsError& e) {
    return e.what();
  }
  return "";
}

TEST(ModelIo, PaperPresetHasThePaperValues) {
  const auto model = load_model("paper");
  std::map<std::string, double> v;
  for (const auto& p : model->parameters())
    v[p.name] = p.value;
  EXPECT_DOUBLE_EQ(v["coulomb.rho1"], 1.038);
  EXPECT_DOUBLE_EQ(v["stribeck.mu1"], 1.0978);
  EXPECT_DOUBLE_EQ(v["stribeck.kappa1"], 6.1264);
  EXPECT_DOUBLE_EQ(v["acceleration_dependence.mu2"], 0.0458);
  EXPECT_DOUBLE_EQ(v["acceleration_dependence.kappa2"], 0.0269);
  EXPECT_DOUBLE_EQ(v["direction_asymmetry.rho2"], 0.8904);
  EXPECT_DOUBLE_EQ(v["acceleration_dependence.mu3"], 0.145);
  EXPECT_DOUBLE_EQ(v["acceleration_dependence.kappa3"], 13.248);
  EXPECT_DOUBLE_EQ(v["acceleration_dependence.kappa4"], 6.0297);
  EXPECT_DOUBLE_EQ(v["core.gamma"], 9.5651);
  EXPECT_DOUBLE_EQ(v["reversal_offset.lambda"], 0.2);
  EXPECT_DOUBLE_EQ(v["core.theta"], 15.5181);
  EXPECT_DOUBLE_EQ(v["core.n"], 2.0);
  EXPECT_DOUBLE_EQ(v["core.sigma"], 1.0);
  EXPECT_EQ(v.size(), 14u);
}

TEST(ModelIo, YamlRoundTripPreservesEveryModel) {
  for (const auto& name : preset_names()) {
    const auto model = load_model(name);
    const auto text = model_to_yaml(*model, {"round trip"});
    const auto back = parse_model(text, name);
    ASSERT_EQ(back->kind(), model->kind()) << text;
    const auto a = model->parameters(), b = back->parameters();
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].name, b[i].name);
      EXPECT_DOUBLE_EQ(a[i].value, b[i].value) << a[i].name;
      EXPECT_EQ(a[i].fixed, b[i].fixed) << a[i].name;
    }
  }
}

TEST(ModelIo, SaveIsAtomicAndLoadable) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("tsmh_model_io_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = dir / "p.yaml";
  save_model(*load_model("paper"), path, {"test"});
  EXPECT_EQ(load_model(path.string())->parameters().size(), 14u);
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir))
    ++files;
  EXPECT_EQ(files, 1) << "no temporary file left behind";
  std::filesystem::remove_all(dir);
}

TEST(ModelIo, ErrorsNameTheField) {
  const std::string core = "model: tsm\ncore: {theta: 15, gamma: 9, n: 2, sigma: 1}\n";
  EXPECT_NE(
      error_of(core + "terms:\n  stribeck: {mu1: 1, kappa1: abc}\n").find("terms.stribeck.kappa1"),
      std::string::npos);
  EXPECT_NE(error_of(core + "terms:\n  stribeck: {mu1: 1}\n").find("terms.stribeck.kappa1"),
            std::string::npos);
  EXPECT_NE(
      error_of(core + "terms:\n  frobnicate: {a: 1}\n").find("terms.frobnicate: unknown term"),
      std::string::npos);
  EXPECT_NE(error_of(core + "terms:\n  coulomb: {rho1: 1, rho9: 2}\n").find("terms.coulomb.rho9"),
            std::string::npos);
  EXPECT_NE(error_of("model: tsm\ncore: {theta: 15, gamma: 9, n: 2, sigma: 0.2}\nterms: {coulomb: "
                     "{rho1: 1}}\n")
                .find("core.sigma"),
            std::string::npos);
  EXPECT_NE(error_of("model: tsm\ncore: {theta: .nan, gamma: 9, n: 2, sigma: 1}\nterms: {coulomb: "
                     "{rho1: 1}}\n")
                .find("core.theta"),
            std::string::npos);
  EXPECT_NE(error_of(core + "terms: {coulomb: {rho1: 1}}\nfixed: [core.nope]\n").find("core.nope"),
            std::string::npos);
  EXPECT_NE(error_of("model: lugre\nparams: {sigma0: 1}\n").find("params.sigma1"),
            std::string::npos);
  EXPECT_NE(error_of("model: unicorn\n").find("model"), std::string::npos);
  EXPECT_NE(error_of("model: tsm\n  bad: [indent\n").find("not valid YAML"), std::string::npos);
  EXPECT_THROW(load_model("/nonexistent/params.yaml"), ParamsError);
}

TEST(ModelIo, ComposedModelWithAddedEffectRoundTrips) {
  TsmModelSpec spec = paper_spec();
  spec.add(TermKind::kViscous).p = {0.12};
  spec.add(TermKind::kTimeVarying).p = {0.001, 0.3, 12.0, 1.5};
  const TsmFrictionModel model(spec);
  const auto back = parse_model(model_to_yaml(model), "composed");
  const auto p = back->parameters();
  const auto find = [&](const std::string& n) {
    for (const auto& q : p)
      if (q.name == n) return q;
    return Parameter{};
  };
  EXPECT_DOUBLE_EQ(find("viscous.c_v").value, 0.12);
  EXPECT_DOUBLE_EQ(find("time_varying.t0").value, 1.5);
  EXPECT_TRUE(find("time_varying.t0").fixed);
  EXPECT_TRUE(find("core.gamma").fixed);
}

}  // namespace
}  // namespace tsmh::estimator
