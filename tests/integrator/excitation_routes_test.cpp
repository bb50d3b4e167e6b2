// The camera's fluorescence split by what excited it (integrator/excitation_routes.h).
#include <gtest/gtest.h>

#include "integrator/excitation_photons.h"
#include "test_scenes.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

// A slab over a white floor under a distant light. The dye absorbs where it
// emits (its band reaches 700 nm, its emission is centred at 650 nm), so in
// full mode its continuations find both light off the floor and re-emitted
// fluorescence.
Scene slab_over_floor(const std::string& mode) {
  SlabSetup s;
  s.mode = mode;
  s.eps_hi = 700;
  std::string json = slab_scene_json(s);
  const std::string materials = R"("materials": {"boundary": {"type": "interface"})";
  json.replace(json.find(materials), materials.size(),
               R"("materials": {"boundary": {"type": "interface"}, "floor": {"type": "diffuse", "albedo": 0.8})");
  const std::string shapes = R"("shapes": [)";
  json.replace(
      json.find(shapes), shapes.size(),
      R"("shapes": [{"type": "box", "min": [-10, -10, -0.02], "max": [10, 10, -0.01], "material": "floor"}, )");
  return load_scene(write_scene("routes_slab_" + mode, json));
}

struct Traced {
  double fluorescence = 0;  // Σ of the paths' fluorescence, averaged over their lanes
  ExcitationRouteSums routes;
};

Traced trace(const Scene& scene, int paths) {
  Traced t;
  PathStats stats;
  const float lambdas[4] = {640.f, 650.f, 660.f, 670.f}, pdf[4] = {1, 1, 1, 1};
  for (int i = 0; i < paths; ++i) {
    Rng rng(test_seed(29), uint64_t(i));
    SampledWavelengths lambda = SampledWavelengths::from_values(lambdas, pdf, 4);
    t.fluorescence +=
        trace_path(scene, Ray{{0, 0, 1}, {0, 0, -1}}, scene.camera_medium, lambda, rng, stats).fluorescence.average(4);
  }
  t.routes = stats.excitation_routes;
  return t;
}

double route_sum(const Traced& t, ExcitationRoute r) { return t.routes.sum[size_t(r)]; }

double total(const Traced& t) {
  double sum = 0;
  for (double s : t.routes.sum) sum += s;
  return sum;
}

}  // namespace

TEST(ExcitationRoutes, DirectModeIsAllConnection) {
  const Traced t = trace(slab_over_floor("direct"), 2000);
  ASSERT_GT(t.fluorescence, 0.0);
  EXPECT_NEAR(total(t), t.fluorescence, 1e-5 * t.fluorescence);
  EXPECT_EQ(route_sum(t, ExcitationRoute::connection), total(t));
}

TEST(ExcitationRoutes, FullModeSplitsTheSameSumByRoute) {
  const Traced t = trace(slab_over_floor("full"), 4000);
  ASSERT_GT(t.fluorescence, 0.0);
  // The routes partition each event's estimate: together they are the camera's fluorescence.
  EXPECT_NEAR(total(t), t.fluorescence, 1e-5 * t.fluorescence);
  EXPECT_GT(route_sum(t, ExcitationRoute::connection), 0.0);
  EXPECT_GT(route_sum(t, ExcitationRoute::continuation_light), 0.0);      // off the floor
  EXPECT_GT(route_sum(t, ExcitationRoute::continuation_reemitted), 0.0);  // the dye's own red, reabsorbed
  EXPECT_EQ(route_sum(t, ExcitationRoute::bounce), 0.0);                  // a distant light has no bounce connection
  EXPECT_EQ(route_sum(t, ExcitationRoute::photons), 0.0);
  for (size_t r = 0; r < kExcitationRoutes; ++r) {
    EXPECT_GE(t.routes.sum_squares[r], 0.0);
    EXPECT_LE(t.routes.events[r], t.routes.events_any);
  }
  // Every event connects; one in two continues.
  EXPECT_LT(t.routes.events[size_t(ExcitationRoute::continuation_light)],
            t.routes.events[size_t(ExcitationRoute::connection)]);
}

TEST(ExcitationRoutes, PhotonsAreOneRoute) {
  SlabSetup s;
  s.mode = "full";
  s.render_extra = R"(, "excitation_estimate": "photons", "excitation_photons": 4096)";
  const Scene scene = load_scene(write_scene("routes_slab_photons", slab_scene_json(s)));
  prepare_excitation_grids(scene, 1);
  const Traced t = trace(scene, 500);
  ASSERT_GT(t.fluorescence, 0.0);
  EXPECT_NEAR(route_sum(t, ExcitationRoute::photons), t.fluorescence, 1e-5 * t.fluorescence);
  EXPECT_EQ(route_sum(t, ExcitationRoute::connection), 0.0);
}

TEST(ExcitationRoutes, ReportGivesEachRoutesShareOfTheMeanAndOfTheSecondMoment) {
  ExcitationRouteSums r;
  r.add_event({1.0, 0, 0, 0, 0});
  r.add_event({1.0, 0, 0, 0, 0});
  r.add_event({0, 0, 2.0, 0, 0});
  r.add_event({0, 0, 0, 0, 0});  // nothing found: not an event of any route
  EXPECT_EQ(describe_excitation_routes(r),
            "connection to the lights 50.0 % / 33.3 % (in 67 % of events), "
            "continuations' light 50.0 % / 66.7 % (in 33 % of events)");
  EXPECT_EQ(describe_excitation_routes(ExcitationRouteSums{}), "");
}
