// Stress: zero-power lights (scale 0, spectrum 0, none at all, beside a bright
// one) and UV-only lights (nothing visible: the image is fluorescence only),
// for every light type, over a fluorescent medium and a diffuse floor.
#include <gtest/gtest.h>

#include "core/error.h"
#include "stress_util.h"

using namespace chlorovdb;
using namespace chlorovdb::stress;

namespace {

// A sphere of chlorophyll-like dye (absorbs 250-480 nm and its red band,
// emits around 680 nm) on a floor, with the lights given.
std::string lit_scene(const std::string& lights, const std::string& mode = "full", const std::string& extra_shapes = "") {
  return subst(R"({
    "render": {"resolution": [8, 8], "wavelengths": 4, "fluorescence": "$MODE"},
    "camera": {"position": [0, 1, 4], "look_at": [0, 0.3, 0], "fov": 35},
    "pigments": {"dye": {"extinction": {"table": {"lambda": [250, 480, 481, 640, 660, 700, 701],
                                                  "value":  [3e4, 3e4, 0,   0,   8e4, 0,   0]}},
                         "quantum_yield": 0.6, "emission": {"gaussian": [680, 12]}}},
    "materials": {"boundary": {"type": "interface"}, "floor": {"type": "diffuse", "albedo": 0.7}},
    "media": {"dye": {"solvent": "water", "pigments": [{"pigment": "dye", "concentration": 20}]}},
    "shapes": [{"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "material": "boundary", "inside": "dye"},
               {"type": "quad", "corner": [-3, 0, -3], "edge_u": [0, 0, 6], "edge_v": [6, 0, 0], "material": "floor"}
               $EXTRA],
    "lights": [$LIGHTS]
  })",
               {{"$MODE", mode}, {"$LIGHTS", lights}, {"$EXTRA", extra_shapes}});
}

const char* kAreaQuad = R"(, {"type": "quad", "corner": [-1, 2.5, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2],
                             "emission": {"spectrum": $S, "scale": $K}})";

std::string area_light(const std::string& spectrum, double scale) {
  return subst(kAreaQuad, {{"$S", spectrum}, {"$K", num(scale)}});
}

// Every light type with one spectrum and scale.
std::string all_light_types(const std::string& spectrum, double scale) {
  return subst(R"({"type": "point", "position": [1, 2, 1], "spectrum": $S, "scale": $K},
                  {"type": "spot", "position": [-1, 2, 1], "look_at": [0, 0, 0], "spectrum": $S, "scale": $K},
                  {"type": "distant", "direction": [0.2, -1, 0.1], "spectrum": $S, "scale": $K},
                  {"type": "environment", "spectrum": $S, "scale": $K})",
               {{"$S", spectrum}, {"$K", num(scale)}});
}

// Spectra that are exactly zero over the camera's range (360-830 nm).
const char* kUvTable = R"({"table": {"lambda": [250, 300, 340, 359.9], "value": [0.2, 1, 0.5, 0]}})";

std::string sanitize_name(std::string s) {
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

}  // namespace

// ---------------------------------------------------------------------------
// Zero power: the image must be exactly black (and finite), in every mode.
// ---------------------------------------------------------------------------
void zero_power(const std::string& mode) {
  for (const std::string which : {"scale0", "spectrum0", "nolights", "environment0", "area0"}) {
    RenderCase c;
    c.name = "zero_power_" + which + "_" + mode;
    if (which == "scale0") c.json = lit_scene(all_light_types("\"D65\"", 0.0), mode, area_light("\"D65\"", 0.0));
    else if (which == "spectrum0") c.json = lit_scene(all_light_types("0", 1.0), mode, area_light("0", 1.0));
    else if (which == "nolights") c.json = lit_scene("", mode);
    else if (which == "environment0") c.json = lit_scene(R"({"type": "environment", "spectrum": "D65", "scale": 0})", mode);
    else c.json = lit_scene("", mode, area_light("\"D65\"", 0.0));  // area0: only an area light, scale 0
    c.check_energy = false;  // the check that matters: exactly zero
    if (const auto o = try_case(c)) {
      EXPECT_EQ(layer_sum(*o, kLayerTotal), 0.0) << c.name << ": light from nowhere";
      EXPECT_EQ(layer_sum(*o, kLayerFluorescence), 0.0) << c.name;
    }
  }
}

TEST(Stress, ZeroPowerFull) { zero_power("full"); }
TEST(Stress, ZeroPowerDirect) { zero_power("direct"); }
TEST(Stress, ZeroPowerReference) { zero_power("reference"); }

// A zero-power light beside a bright one: the sampler must never pick it with
// probability 0 and divide by that.
TEST(Stress, ZeroPowerBesideBrightLight) {
  for (const std::string mode : {"full", "direct", "reference"}) {
    RenderCase c;
    c.name = "zero_beside_bright_" + mode;
    c.json = lit_scene(all_light_types("\"D65\"", 0.0) + R"(, {"type": "environment", "spectrum": "D65", "scale": 1})",
                       mode, area_light("0", 1.0));
    try_case(c);
  }
}

// ---------------------------------------------------------------------------
// UV-only lights: nothing reaches the camera but fluorescence.
// ---------------------------------------------------------------------------
void uv_only(const std::string& type) {
  for (const std::string mode : {"full", "direct", "reference"}) {
    RenderCase c;
    c.name = "uv_only_" + type + "_" + mode;
    std::string lights, shapes;
    if (type == "area") shapes = area_light(kUvTable, 20.0);
    else if (type == "point") lights = subst(R"({"type": "point", "position": [1, 2, 1], "spectrum": $S, "scale": 20})", {{"$S", kUvTable}});
    else if (type == "spot") lights = subst(R"({"type": "spot", "position": [0, 2, 0], "look_at": [0, 0, 0], "spectrum": $S, "scale": 20})", {{"$S", kUvTable}});
    else if (type == "distant") lights = subst(R"({"type": "distant", "direction": [0, -1, 0], "spectrum": $S, "scale": 5})", {{"$S", kUvTable}});
    else lights = subst(R"({"type": "environment", "spectrum": $S, "scale": 2})", {{"$S", kUvTable}});
    c.json = lit_scene(lights, mode, shapes);
    c.spp = 16;
    if (const auto o = try_case(c)) {
      EXPECT_EQ(layer_sum(*o, kLayerNonFluorescence), 0.0) << c.name << ": UV light seen directly or reflected";
      EXPECT_GT(layer_sum(*o, kLayerFluorescence), 0.0) << c.name << ": no fluorescence under UV";
    }
  }
}

TEST(Stress, UvOnlyAreaLight) { uv_only("area"); }
TEST(Stress, UvOnlyPointLight) { uv_only("point"); }
TEST(Stress, UvOnlySpotLight) { uv_only("spot"); }
TEST(Stress, UvOnlyDistantLight) { uv_only("distant"); }
TEST(Stress, UvOnlyEnvironmentLight) { uv_only("environment"); }

// Lights so bright or so dim that float products under- or overflow (scale 1e-30 .. 1e30):
// either a clean InputError at load or a finite image.
TEST(Stress, ExtremeLightScales) {
  for (double k : {1e-30, 1e-20, 1e20, 1e30}) {
    RenderCase c;
    c.name = "light_scale_" + sanitize_name(num(k));
    c.json = lit_scene(subst(R"({"type": "environment", "spectrum": "D65", "scale": $K},
                                 {"type": "distant", "direction": [0, -1, 0], "spectrum": {"gaussian": [300, 10]}, "scale": $K})",
                             {{"$K", num(k)}}),
                       "full");
    try {
      render_case(c);
    } catch (const InputError&) {
      // Refusing absurd scales at load, with a message, is fine.
    } catch (const std::exception& e) {
      ADD_FAILURE() << c.name << ": " << typeid(e).name() << ": " << e.what() << " (not an InputError)";
    }
  }
}
