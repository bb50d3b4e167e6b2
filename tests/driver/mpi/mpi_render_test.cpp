// chlorovdb-mpi under `mpirun -np 2`: the ranks split the samples and reduce the
// film to rank 0, whose image equals the single-process render within float
// rounding (the compositing layers too); each rank's checkpoint is a part that
// `chlorovdb merge` accepts.
// Built and registered only with CHLOROVDB_MPI=ON (label "mpi").
#include <cmath>

#include "../child_process.h"
#include "checkpoint/checkpoint.h"
#include "io/image.h"

namespace chlorovdb::test {
namespace {

std::vector<std::string> args_for(std::vector<std::string> head, const std::filesystem::path& out, const std::string& ckpt) {
  const std::vector<std::string> tail = {"render", std::string(CHLOROVDB_SOURCE_DIR) + "/scenes/default.json", "-o", out.string(),
                                         "--resolution", "32x24", "--wavelengths", "4", "--seed", "3", "--spp", "16",
                                         "--threads", "1", "-q", "--checkpoint", ckpt, "--aovs", "alpha,depth,normal,albedo"};
  head.insert(head.end(), tail.begin(), tail.end());
  return head;
}

void expect_close(const Image& a, const Image& b) {
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  ASSERT_EQ(a.layers.size(), b.layers.size());
  for (size_t l = 0; l < a.layers.size(); ++l) {
    const auto &x = a.layers[l].pixels, &y = b.layers[l].pixels;
    ASSERT_EQ(x.size(), y.size());
    float scale = 0;
    for (float v : y)
      if (std::isfinite(v)) scale = std::max(scale, std::abs(v));
    for (size_t i = 0; i < x.size(); ++i)
      if (x[i] != y[i])  // equal, or both +inf (the depth where no sample hit a surface)
        ASSERT_NEAR(x[i], y[i], 4e-7f * std::max(std::abs(x[i]), std::abs(y[i])) + 1e-6f * scale) << a.layers[l].name << " " << i;
  }
}

TEST(MpiRender, TwoRanksEqualTheSingleProcessRender) {
  const TestDir dir;
  std::vector<std::string> mpirun = {CHLOROVDB_MPIEXEC, "-np", "2", "--oversubscribe"};
  if (::geteuid() == 0) mpirun.push_back("--allow-run-as-root");
  mpirun.push_back(CHLOROVDB_MPI_EXE);
  const auto mpi = run(args_for(mpirun, dir / "mpi.exr", (dir / "mpi.ckpt").string()), dir / "mpi.log");
  ASSERT_EQ(mpi.status, 0) << mpi.output;
  const auto single = run(args_for({CHLOROVDB_EXE}, dir / "single.exr", (dir / "single.ckpt").string()), dir / "single.log");
  ASSERT_EQ(single.status, 0) << single.output;

  const Image a = read_exr(dir / "mpi.exr"), b = read_exr(dir / "single.exr");
  ASSERT_NE(a.find_layer("depth"), nullptr) << "the AOVs are summed over the ranks too";
  expect_close(a, b);
  const MetadataValue* ranks = a.metadata.find("mpi_ranks");
  ASSERT_NE(ranks, nullptr);
  EXPECT_EQ(std::get<int>(*ranks), 2);
  EXPECT_EQ(std::get<int>(*a.metadata.find("spp")), 16);
  EXPECT_EQ(std::get<std::string>(*a.metadata.find("sample_ranges")), "0:16");

  // Rank r rendered samples [8r, 8r + 8) and left its own checkpoint.
  const CheckpointHeader r0 = read_checkpoint_header(dir / "mpi.ckpt.rank0of2"), r1 = read_checkpoint_header(dir / "mpi.ckpt.rank1of2");
  EXPECT_EQ(r0.sample_first, 0);
  EXPECT_EQ(r0.samples_done, 8);
  EXPECT_EQ(r1.sample_first, 8);
  EXPECT_EQ(r1.samples_done, 8);
  const auto merged = run({CHLOROVDB_EXE, "merge", (dir / "mpi.ckpt.rank1of2").string(), (dir / "mpi.ckpt.rank0of2").string(),
                           "-o", (dir / "merged.exr").string()},
                          dir / "merge.log");
  ASSERT_EQ(merged.status, 0) << merged.output;
  expect_close(read_exr(dir / "merged.exr"), b);
}

}  // namespace
}  // namespace chlorovdb::test
