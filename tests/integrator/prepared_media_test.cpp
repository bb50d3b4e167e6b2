// PreparedMedia: each medium of the scene prepared once per path, on first use,
// whether it lives in place (the first two) or in the overflow storage.
#include <fmt/format.h>

#include "integrator/transport.h"
#include "test_scenes.h"

namespace chlorovdb::test {

TEST(PreparedMedia, EveryMediumPreparedOnceInAnyOrder) {
  std::string media;
  for (int i = 0; i < 4; ++i)
    media += fmt::format(R"({}"m{}": {{"solvent": "none", "scattering": {{"coefficient": {}, "g": 0}}}})", i ? ", " : "", i,
                         10 * (i + 1));
  const auto path = write_scene("prepared_media", R"({
  "render": {"resolution": [4, 4], "spp": 1},
  "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
  "media": {)" + media + R"(},
  "lights": [{"type": "distant", "direction": [0, 0, -1], "spectrum": 1}]
})");
  const Scene scene = load_scene(path);
  ASSERT_EQ(scene.media.size(), 4u);
  const SampledWavelengths lambda = SampledWavelengths::sample_visible(0.3f, 4);
  PreparedMedia prepared(scene, lambda);
  for (const int m : {3, 0, 2, 1, 3, 0}) {
    const PreparedMedium& p = prepared[m];
    EXPECT_EQ(&p, &prepared[m]) << "prepared once, then reused";
    const float expected = prepare(scene.media[m], lambda).sigma_t_constant[0];
    EXPECT_EQ(p.sigma_t_constant[0], expected) << "medium " << m;
    EXPECT_GT(expected, 0.f);
  }
}

}  // namespace chlorovdb::test
