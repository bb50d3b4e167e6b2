// `chlorovdb voxelize` as the command line sees it: CLI11 parsing into VoxelizeArgs, flag
// checks, and the command line recorded as the grid's provenance.
#include <CLI/CLI.hpp>

#include "voxelize/voxelize_command.h"
#include "voxelize_test_util.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

// Parses `chlorovdb voxelize ...` into args; returns false if CLI11 refuses the command line.
bool parse(std::vector<std::string> words, cli::VoxelizeArgs& args) {
  CLI::App app{"test"};
  cli::add_voxelize_subcommand(app, args);
  words.insert(words.begin(), "voxelize");
  std::reverse(words.begin(), words.end());  // CLI11 takes a reversed vector
  try {
    app.parse(words);
  } catch (const CLI::ParseError&) {
    return false;
  }
  return app.got_subcommand("voxelize");
}

}  // namespace

TEST(VoxelizeCommand, ShellWithNonCubicVoxelsEndToEnd) {
  const auto mesh = write_obj(make_quad({-0.01f, 0.f, -0.01f}, {0, 0, 0.02f}, {0.02f, 0, 0}), "cmd_leaf.obj");
  const auto out = temp_path("cmd_leaf.vdb");
  cli::VoxelizeArgs args;
  ASSERT_TRUE(parse({mesh.string(), "-o", out.string(), "--mode", "shell", "--thickness", "0.0002", "--voxel-size",
                     "0.0005,0.00005,0.0005", "--concentration", "30", "--unit", "uM", "--grid-name", "chl", "-q"},
                    args));
  EXPECT_EQ(args.voxel_size, "0.0005,0.00005,0.0005");
  EXPECT_EQ(cli::voxelize(args), 0);
  const VoxelGrid g = load_concentration_grid(out, "chl");
  EXPECT_EQ(g.metadata().unit, "uM");
  EXPECT_NE(g.metadata().provenance.find(cli::voxelize_command_line(args)), std::string::npos);
  EXPECT_NE(g.metadata().provenance.find("--voxel-size 0.0005,0.00005,0.0005"), std::string::npos);
  // 0.2 mm across with 0.05 mm voxels along y.
  double across = 0;
  for (int j = -10; j <= 10; ++j) across += g.voxel(0, j, 0) * 0.00005;
  EXPECT_NEAR(across / 30.0, 0.0002, 2e-6);
}

TEST(VoxelizeCommand, SpillWithScaleAndTranslate) {
  // A 40 x 40 mm footprint given in mm.
  const auto mesh = write_obj(make_quad({0, 0, 0}, {0, 0, 40}, {40, 0, 0}), "cmd_spill.obj");
  const auto out = temp_path("cmd_spill.vdb");
  cli::VoxelizeArgs args;
  ASSERT_TRUE(parse({mesh.string(), "-o", out.string(), "--mode", "spill", "--depth", "0.001", "--voxel-size",
                     "0.0005", "--scale", "0.001", "--translate", "0.1,0.2,0.3", "--profile", "linear", "--gradient",
                     "1,3", "--axis", "x", "-q"},
                    args));
  EXPECT_EQ(cli::voxelize(args), 0);
  const VoxelGrid g = load_concentration_grid(out, "density");
  EXPECT_NEAR(integral(g) / (0.04 * 0.04 * 0.001 * 2.0), 1.0, 0.01);  // mean of the gradient: 2
  EXPECT_NEAR(voxel_at(g, {0.12f, 0.2005f, 0.32f}), 2.f, 0.02f);
}

TEST(VoxelizeCommand, FlagErrorsNameTheFlag) {
  const auto mesh = write_obj(make_box({{0, 0, 0}, {0.01f, 0.01f, 0.01f}}), "cmd_box.obj");
  auto error_for = [&](std::vector<std::string> extra) {
    cli::VoxelizeArgs args;
    std::vector<std::string> words{mesh.string(), "-o", temp_path("cmd_never.vdb").string()};
    words.insert(words.end(), extra.begin(), extra.end());
    if (!parse(words, args)) return std::string("(CLI11 refused)");
    return error_of([&] { cli::voxelize(args); });
  };
  EXPECT_NE(error_for({"--voxel-size", "1mm"}).find("--voxel-size = 1mm"), std::string::npos);
  EXPECT_NE(error_for({"--voxel-size", "0.001,0.002"}).find("vx,vy,vz"), std::string::npos);
  EXPECT_NE(error_for({"--voxel-size", "0.001", "--mode", "cloud"}).find("--mode = cloud"), std::string::npos);
  EXPECT_NE(error_for({"--voxel-size", "0.001", "--thickness", "0.001"}).find("only applies to --mode shell"),
            std::string::npos);
  EXPECT_NE(error_for({"--voxel-size", "0.001", "--profile", "linear"}).find("--gradient"), std::string::npos);
  EXPECT_NE(error_for({"--voxel-size", "0.001", "--profile", "grid", "--concentration", "3"}).find("no effect"),
            std::string::npos);
  EXPECT_NE(error_for({"--voxel-size", "0.001", "--axis", "w", "--profile", "linear", "--gradient", "1,2"})
                .find("--axis = w"),
            std::string::npos);
  EXPECT_EQ(error_for({}), "(CLI11 refused)");  // --voxel-size is required
}
