// Every mediator parameter has a plain-language label for the panel that fits its column.
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "app/param_labels.h"
#include "mediator/params.h"

namespace gk::app {
namespace {

TEST(ParamLabels, EveryParameterHasAShortDistinctPlainLabel) {
  std::set<std::string> seen;
  for (const ParamInfo& info : mediator_param_infos()) {
    const std::string label(param_label(info.name));
    EXPECT_NE(label, info.name) << "no plain label for " << info.name;
    EXPECT_EQ(label.find('_'), std::string::npos) << label;
    EXPECT_LE(label.size(), 26u) << label << " does not fit the panel's label column";
    EXPECT_TRUE(seen.insert(label).second) << "two parameters labelled " << label;
  }
  EXPECT_STREQ(param_label("not_a_parameter"), "not_a_parameter");
}

}  // namespace
}  // namespace gk::app
