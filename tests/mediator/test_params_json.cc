// Mediator parameters written as JSON read back to the same values.
#include <gtest/gtest.h>

#include "mediator/params.h"

namespace gk {
namespace {

TEST(ParamsJson, WrittenParametersReadBackUnchanged) {
  // Every parameter away from its default, to a value inside its limits.
  MediatorParams p;
  for (const ParamInfo& info : mediator_param_infos()) {
    if (info.kind == ParamInfo::Kind::kBool) {
      p.*info.b = !(p.*info.b);
    } else {
      p.*info.f = info.min_value + 0.37f * (info.max_value - info.min_value);
    }
  }
  p.min_playback_rate = 0.55f;
  p.max_playback_rate = 1.1f;
  p.mode = MediatorMode::kRate;
  p.seed = 1234567890123ull;
  const std::string text = mediator_params_to_json(p);
  EXPECT_NE(text.find("\"torsion_limit_deg\""), std::string::npos) << text;
  EXPECT_NE(text.find("\"mode\": \"rate\""), std::string::npos) << text;
  MediatorParams back;
  ASSERT_TRUE(parse_mediator_params_json(text, "written.json", &back).ok()) << text;
  for (const ParamInfo& info : mediator_param_infos()) {
    if (info.kind == ParamInfo::Kind::kBool) {
      EXPECT_EQ(back.*info.b, p.*info.b) << info.name;
    } else {
      EXPECT_EQ(back.*info.f, p.*info.f) << info.name;  // bit-exact, not near
    }
  }
  EXPECT_EQ(back.mode, MediatorMode::kRate);
  EXPECT_EQ(back.seed, p.seed);
  // Defaults are written as their short decimals.
  EXPECT_NE(mediator_params_to_json(MediatorParams{}).find("\"velocity_halflife_s\": 0.05,"),
            std::string::npos)
      << mediator_params_to_json(MediatorParams{});
}

}  // namespace
}  // namespace gk
