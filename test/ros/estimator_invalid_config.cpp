// An invalid configuration is fatal: estimator_node logs ROS_FATAL naming
// the key and the value (the ConfigError text) and exits with status 2.
#include "estimator_test_support.h"

namespace pc_ekf::test {
namespace {

struct BadConfig {
  std::string name;                   // node name (its private parameters stay on the master)
  std::string args;                   // _param:=value arguments
  std::vector<std::string> expected;  // on stderr
};

ToolRun startEstimator(const BadConfig& c) {
  // `timeout`: a node that wrongly starts would spin forever.
  return runCommand("timeout 20 " + executableBeside("estimator_node") + " __name:=" + c.name +
                    " " + c.args);
}

TEST(EstimatorInvalidConfig, ExitsNonZeroNamingTheKey) {
  const std::string file = "_config_file:=" + configPath("speed_bump.yaml");
  const std::vector<BadConfig> cases{
      {"bad_pdf_every", file + " _node/pdf_every:=0", {"key 'node.pdf_every'", "'0'"}},
      {"bad_update", file + " _filter/update:=fast", {"key 'filter.update'", "'fast'", "paper"}},
      {"unknown_key", file + " _pc/orderr:=4", {"key 'pc.orderr'", "unknown key"}},
      {"same_joints", file + " _node/joints/right:=left_suspension", {"key 'node.joints.right'"}},
      {"bad_flag",
       file + " _node/reset_on_time_jump:=maybe",
       {"key 'node.reset_on_time_jump'", "'maybe'"}},
      {"missing_file",
       "_config_file:=/nonexistent/pc_ekf.yaml",
       {"/nonexistent/pc_ekf.yaml", "cannot open"}},
      {"no_config", "", {"key 'uncertain'"}},
  };
  for (const BadConfig& c : cases) {
    const ToolRun r = startEstimator(c);
    EXPECT_EQ(r.status, 2) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find("FATAL"), std::string::npos) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find("invalid configuration"), std::string::npos) << c.name << ": " << r.err;
    for (const auto& text : c.expected) {
      EXPECT_NE(r.err.find(text), std::string::npos) << c.name << ": '" << text << "' in " << r.err;
    }
  }
}

TEST(EstimatorInvalidConfig, PrivateParametersOverrideTheFile) {
  // The file alone is valid; the override makes it invalid, and the message
  // names both sources.
  const ToolRun r =
      startEstimator({"override",
                      "_config_file:=" + configPath("speed_bump.yaml") + " _collocation/points:=5",
                      {}});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("key 'collocation.points'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("speed_bump.yaml + rosparam /override"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_invalid_config_tester");
}
