// A reference interrupted at k samples, written to EXR, read back and resumed
// equals an uninterrupted render of the same samples up to float rounding.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>

#include "analysis/analytic_slab.h"
#include "analysis/progressive.h"
#include "io/image.h"
#include "scene/scene_loader.h"

using namespace chlorovdb;

TEST(Reference, InterruptedThenResumedEqualsUninterrupted) {
  SlabCase slab = analytic_case("slab_linear");
  slab.name = "reference_resume";
  slab.resolution = 8;
  const auto dir = chlorovdb::test::scratch_dir("analysis_tests");
  const Scene scene = load_scene(write_slab_scene(slab, dir));
  const int total = 40;

  ReferenceOptions o;
  o.spp = total;
  o.seed = 77;
  o.checkpoint_seconds = 0;  // a checkpoint after every pass
  const ReferenceResult whole = continue_reference(scene, nullptr, 0, o, nullptr);
  ASSERT_EQ(whole.spp_done, total);
  ASSERT_FALSE(whole.interrupted);

  // First session: stop (as Ctrl-C would) once a checkpoint holds >= 5 samples.
  std::atomic<bool> stop{false};
  const auto exr = dir / "reference_resume.exr";
  int written = 0;
  o.stop = &stop;
  const ReferenceResult first = continue_reference(scene, nullptr, 0, o, [&](const Image& image, int spp_done) {
    Image copy = image;
    copy.metadata.set("spp_done", spp_done);
    write_exr(exr, copy);
    written = spp_done;
    if (spp_done >= 5) stop = true;
  });
  ASSERT_TRUE(first.interrupted);
  ASSERT_GE(written, 5);
  ASSERT_LT(written, total);
  EXPECT_EQ(first.spp_done, written);

  // Second session: from the file alone.
  const Image partial = read_exr(exr);
  const int k = std::get<int>(*partial.metadata.find("spp_done"));
  EXPECT_EQ(k, written);
  stop = false;
  const ReferenceResult resumed = continue_reference(scene, &partial, k, o, nullptr);
  ASSERT_EQ(resumed.spp_done, total);

  ASSERT_EQ(resumed.image.layers.size(), whole.image.layers.size());
  double max_rel = 0;
  for (size_t l = 0; l < whole.image.layers.size(); ++l) {
    const auto& a = whole.image.layers[l].pixels;
    const auto& b = resumed.image.layers[l].pixels;
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
      EXPECT_NEAR(b[i], a[i], 4e-7f * std::abs(a[i]) + 1e-12f) << "layer " << l << " value " << i;
      if (a[i] != 0) max_rel = std::max(max_rel, std::abs(double(b[i]) / a[i] - 1));
    }
  }
  std::printf("resumed at %d of %d spp: largest relative difference %.2e\n", k, total, max_rel);
}
