// Hostile scene files (issue 21): each is refused with an InputError naming the
// file, the key path and the value, where before it crashed, ran away or was
// silently accepted. The same inputs seed fuzz/seeds/scene.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "grids/vdb_file.h"
#include "scene/param_reader.h"
#include "scene/scene_loader.h"

using namespace chlorovdb;

namespace {

std::filesystem::path write(const std::string& name, const std::string& text) {
  const auto path = test::scratch_dir("hostile_scene_tests") / name;
  std::ofstream(path) << text;
  return path;
}

std::string load_error(const std::string& json) {
  try {
    load_scene(write("hostile.json", json));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A scene that loads; `camera`, `render`, `lights` and `extra` replace its parts.
std::string scene(const std::string& camera = R"({"position": [0, 1, 5], "look_at": [0, 0, 0]})",
                  const std::string& render = R"({"resolution": [8, 8], "spp": 1})",
                  const std::string& lights = R"([{"type": "point", "position": [0, 3, 0]}])",
                  const std::string& extra = "") {
  return R"({"render": )" + render + R"(, "camera": )" + camera + R"(, "lights": )" + lights +
         R"(, "materials": {"w": {"type": "diffuse"}},
  "shapes": [{"type": "quad", "corner": [-1, 0, -1], "edge_u": [0, 0, 2], "edge_v": [2, 0, 0], "material": "w"}])" +
         extra + "}";
}

void expect_error(const std::string& json, std::initializer_list<const char*> parts) {
  const std::string e = load_error(json);
  ASSERT_FALSE(e.empty()) << "accepted: " << json.substr(0, 200);
  EXPECT_NE(e.find("hostile.json"), std::string::npos) << e;
  for (const char* p : parts) EXPECT_NE(e.find(p), std::string::npos) << "missing \"" << p << "\" in: " << e;
}

}  // namespace

TEST(HostileScene, BaseSceneLoads) { EXPECT_EQ(load_error(scene()), ""); }

TEST(HostileScene, DuplicateKeysAreRefusedWhateverTheirOrder) {
  // The later spp used to win, unbounded by any check.
  expect_error(scene(R"({"position": [0, 1, 5], "look_at": [0, 0, 0]})", R"({"spp": 2, "resolution": [8, 8], "spp": 16777216})"),
               {"render.spp", "duplicate key"});
  expect_error(scene(R"({"position": [0, 1, 5], "look_at": [0, 0, 0], "position": [0, 1, 6]})"), {"camera.position", "duplicate key"});
  expect_error(R"({"camera": {"position": [0, 1, 5], "look_at": [0, 0, 0]}, "camera": {}})", {"camera", "duplicate key"});
  // Inside arrays of objects the path names the element.
  expect_error(scene(R"({"position": [0, 1, 5], "look_at": [0, 0, 0]})", R"({"spp": 1})",
                     R"([{"type": "point", "position": [0, 3, 0]}, {"type": "point", "type": "spot"}])"),
               {"lights[1].type", "duplicate key"});
}

TEST(HostileScene, DeepNestingIsRefusedBeforeParsing) {
  // 1e5 and 1e6 levels used to overflow the stack.
  for (const size_t depth : {size_t(65), size_t(100000), size_t(1000000)}) {
    const std::string nested = std::string(depth, '[') + std::string(depth, ']');
    expect_error(R"({"camera": {"position": [0, 1, 5], "look_at": )" + nested + "}}", {"camera.look_at", "nested deeper than 64"});
  }
  // 64 levels is still JSON the reader accepts (and the getter then refuses as a vector).
  const std::string ok = std::string(62, '[') + std::string(62, ']');
  expect_error(R"({"camera": {"position": [0, 1, 5], "look_at": )" + ok + "}}", {"camera.look_at"});
  EXPECT_EQ(load_error(scene()).find("nested"), std::string::npos);
}

TEST(HostileScene, ParseTextNamesItsOrigin) {
  try {
    ParamReader::parse_text(R"({"a": 1, "a": 2})", "command line: --set x");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("command line: --set x: a: duplicate key"), std::string::npos) << e.what();
  }
}

TEST(HostileScene, CameraUpMustBeNonZeroAndNotAlongTheView) {
  expect_error(scene(R"({"position": [0, 1, 5], "look_at": [0, 0, 0], "up": [0, 0, 0]})"), {"camera.up", "zero vector"});
  expect_error(scene(R"({"position": [0, 1, 5], "look_at": [0, 0, 0], "up": [0, -2, -10]})"), {"camera.up", "parallel"});
  expect_error(scene(R"({"position": [0, 0, 5], "look_at": [0, 0, 0], "up": [1e-9, 0, 1]})"), {"camera.up", "parallel"});
}

TEST(HostileScene, PositionsBeyondFloatAreRefused) {
  expect_error(scene(R"({"position": [0, 1e39, 5], "look_at": [0, 0, 0]})"), {"camera.position", "1e+39", "single precision"});
  expect_error(scene(R"({"position": [0, 1, 5], "look_at": [-1e39, 0, 0]})"), {"camera.look_at", "single precision"});
  // Each fits a float, their distance does not.
  expect_error(scene(R"({"position": [2e38, 0, 0], "look_at": [-2e38, 0, 0]})"), {"camera.look_at", "too far"});
  expect_error(scene(R"({"position": [0, 1, 5], "look_at": [0, 0, 0]})", R"({"spp": 1})",
                     R"([{"type": "point", "position": [1e39, 3, 0]}])"),
               {"lights[0].position", "single precision"});
  expect_error(scene(R"({"position": [0, 1, 5], "look_at": [0, 0, 0]})", R"({"spp": 1})",
                     R"([{"type": "distant", "direction": [0, -1e39, 0]}])"),
               {"lights[0].direction"});
}

TEST(HostileScene, SpotLightLookAtMustDifferFromPosition) {
  expect_error(scene(R"({"position": [0, 1, 5], "look_at": [0, 0, 0]})", R"({"spp": 1})",
                     R"([{"type": "spot", "position": [0, 3, 0], "look_at": [0, 3, 0]}])"),
               {"lights[0].look_at", "must differ from \"position\""});
  EXPECT_EQ(load_error(scene(R"({"position": [0, 1, 5], "look_at": [0, 0, 0]})", R"({"spp": 1})",
                             R"([{"type": "spot", "position": [0, 3, 0], "look_at": [0, 0, 0]}])")),
            "");
}

TEST(HostileScene, IntegersMustFitTheirType) {
  const std::string cam = R"({"position": [0, 1, 5], "look_at": [0, 0, 0]})";
  expect_error(scene(cam, R"({"spp": 4294967297})"), {"render.spp", "[1, 16777216]"});
  expect_error(scene(cam, R"({"spp": 18446744073709551615})"), {"render.spp"});
  expect_error(scene(cam, R"({"max_depth": -9223372036854775808})"), {"render.max_depth"});
  expect_error(scene(cam, R"({"spp": 2.5})"), {"render.spp", "integer"});
  expect_error(scene(cam, R"({"seed": -1})"), {"render.seed"});
  expect_error(scene(cam, R"({"resolution": [4294967312, 12]})"), {"render.resolution"});
  // Every 64-bit seed is valid.
  EXPECT_EQ(load_scene(write("seed.json", scene(cam, R"({"resolution": [8, 8], "seed": 18446744073709551615})"))).settings.seed,
            UINT64_MAX);
}

TEST(HostileScene, FloatsMustFitSinglePrecision) {
  const std::string cam = R"({"position": [0, 1, 5], "look_at": [0, 0, 0]})";
  expect_error(scene(cam, R"({"exposure": 1e39})"), {"render.exposure", "[-40, 40]"});
  expect_error(scene(R"({"position": [0, 1, 5], "look_at": [0, 0, 0], "fov": 1e300})"), {"camera.fov"});
  expect_error(scene(cam, R"({"spp": 1})", R"([{"type": "point", "position": [0, 3, 0], "scale": 1e39}])"), {"lights[0].scale"});
}

TEST(HostileScene, SellmeierWithAPoleOrImaginaryIndexIsRefused) {
  const auto glass = [](const std::string& B, const std::string& C) {
    return R"({"render": {"resolution": [8, 8], "spp": 1}, "camera": {"position": [0, 1, 5], "look_at": [0, 0, 0]},
      "lights": [{"type": "point", "position": [0, 3, 0]}],
      "materials": {"g": {"type": "dielectric", "ior": {"sellmeier": {"B": )" +
           B + R"(, "C": )" + C + R"(}}}}, "shapes": [{"type": "sphere", "radius": 1, "material": "g"}]})";
  };
  expect_error(glass("[1, 0, 0]", "[0.25, 0, 0]"), {"materials.g.ior.sellmeier", "pole", "500.0 nm"});
  expect_error(glass("[-5, 0, 0]", "[0.01, 0, 0]"), {"materials.g.ior.sellmeier", "n^2"});
  // A pole at 249 nm, just outside: n = 11 at 250 nm.
  expect_error(glass("[1, 0, 0]", "[0.062, 0, 0]"), {"materials.g.ior.sellmeier", "n^2 = 126"});
  EXPECT_EQ(load_error(glass("[1, 0, 0]", "[0.05, 0, 0]")), "");  // pole at 224 nm: n = 2.4 at 250 nm
  // BK7 (Schott) loads.
  EXPECT_EQ(load_error(glass("[1.03961212, 0.231792344, 1.01046945]", "[0.00600069867, 0.0200179144, 103.560653]")), "");
}

TEST(HostileScene, GridFieldsBeyondAnyConcentrationAreRefused) {
  DenseGrid g({4, 4, 4}, 1.f);
  g.world_from_index = Transform::scale(Vec3(0.25f));
  g.metadata.name = "density";
  g.metadata.unit = "uM";
  const auto one = test::scratch_dir("hostile_scene_tests") / "one.vdb";
  write_concentration_grid(one, g);
  for (float& v : g.values) v = 1e30f;
  const auto huge = test::scratch_dir("hostile_scene_tests") / "huge.vdb";
  write_concentration_grid(huge, g);
  const auto medium = [](const std::string& field) {
    return R"({"render": {"resolution": [8, 8], "spp": 1}, "camera": {"position": [0.5, 0.5, 5], "look_at": [0.5, 0.5, 0]},
      "lights": [{"type": "point", "position": [0, 3, 0]}],
      "pigments": {"chl": {"extinction": "chlorophyll_a"}},
      "media": {"m": {"solvent": "none", "pigments": [{"pigment": "chl", )" +
           field + "}]}}}";
  };
  EXPECT_EQ(load_error(medium(R"("grid": {"file": "one.vdb"})")), "");
  expect_error(medium(R"("grid": {"file": "huge.vdb"})"), {"media.m.pigments[0].grid", "1e+24 mol/L", "at most 100"});
  expect_error(medium(R"("grid": {"file": "one.vdb", "scale": 3e38})"), {"media.m.pigments[0].grid", "3e+32 mol/L"});
  expect_error(medium(R"("concentration": 1e30)"), {"media.m.pigments[0].concentration", "mol/L"});
  expect_error(medium(R"("concentration": 1e39)"), {"media.m.pigments[0].concentration", "single precision"});
}

TEST(HostileScene, TruncatedGridFileIsRefused) {
  DenseGrid g({8, 8, 8}, 1.f);
  g.world_from_index = Transform::scale(Vec3(0.1f));
  g.metadata.name = "density";
  const auto whole = test::scratch_dir("hostile_scene_tests") / "whole.vdb";
  write_concentration_grid(whole, g);
  std::ifstream in(whole, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Cut in the header, the metadata, the descriptor and the grid data.
  for (const size_t keep : {size_t(10), size_t(60), size_t(200), bytes.size() / 2, bytes.size() - 1}) {
    const auto cut = test::scratch_dir("hostile_scene_tests") / "cut.vdb";
    std::ofstream(cut, std::ios::binary) << bytes.substr(0, keep);
    try {
      inspect_vdb(cut);
      ADD_FAILURE() << "accepted a .vdb cut to " << keep << " of " << bytes.size() << " bytes";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("cut.vdb"), std::string::npos) << e.what();
    }
    EXPECT_THROW(load_concentration_grid(cut, "density", {}), InputError) << keep;
  }
  EXPECT_NO_THROW(inspect_vdb(whole));
}

TEST(HostileScene, SensorRegionsMustBeWholePixelsInsideTheImage) {
  const std::string cam = R"({"position": [0, 1, 5], "look_at": [0, 0, 0]})", render = R"({"resolution": [8, 6], "spp": 1})",
                    lights = R"([{"type": "point", "position": [0, 3, 0]}])";
  const auto sensors = [&](const std::string& s) { return scene(cam, render, lights, R"(, "sensors": )" + s); };
  const Scene ok = load_scene(write("sensors.json", sensors(R"({"glow": {"region": [1, 2, 5, 6]}, "dark": {"region": [0, 0, 8, 1]}})")));
  ASSERT_EQ(ok.sensors.size(), 2u);
  EXPECT_EQ(ok.sensors[0].name, "dark");  // by name
  EXPECT_EQ(ok.sensors[1].name, "glow");
  EXPECT_EQ(ok.sensors[1].x0, 1);
  EXPECT_EQ(ok.sensors[1].y1, 6);
  expect_error(sensors(R"({"glow": {"region": [1, 2, 9, 6]}})"), {"sensors.glow.region", "[1,2,9,6]", "outside the 8x6 image"});
  expect_error(sensors(R"({"glow": {"region": [-1, 2, 3, 4]}})"), {"sensors.glow.region", "outside"});
  expect_error(sensors(R"({"glow": {"region": [5, 2, 1, 6]}})"), {"sensors.glow.region", "inverted"});
  expect_error(sensors(R"({"glow": {"region": [1, 2, 1, 6]}})"), {"sensors.glow.region", "empty"});
  expect_error(sensors(R"({"glow": {"region": [1.5, 2, 3, 6]}})"), {"sensors.glow.region", "1.5", "whole numbers"});
  expect_error(sensors(R"({"glow": {"region": [1, 2, 3]}})"), {"sensors.glow.region", "[x0, y0, x1, y1]"});
  expect_error(sensors(R"({"glow": {"region": [1, 2, 3, 4], "shape": "disk"}})"), {"sensors.glow.shape", "unknown key"});
  expect_error(sensors(R"({"glow": {}})"), {"sensors.glow.region"});
  expect_error(sensors(R"([1, 2])"), {"sensors", "object"});
}

TEST(HostileScene, AovsMustBeKnownNames) {
  const std::string cam = R"({"position": [0, 1, 5], "look_at": [0, 0, 0]})";
  const Scene ok = load_scene(write("aovs.json", scene(cam, R"({"resolution": [8, 8], "spp": 1, "aovs": ["depth", "alpha"]})")));
  EXPECT_EQ(ok.settings.aovs, AovMask(kAovDepth | kAovAlpha));
  EXPECT_EQ(load_scene(write("no_aovs.json", scene())).settings.aovs, 0u);
  expect_error(scene(cam, R"({"resolution": [8, 8], "aovs": ["alpha", "nromal"]})"),
               {"render.aovs", "\"nromal\" is not an AOV", "did you mean \"normal\""});
  expect_error(scene(cam, R"({"resolution": [8, 8], "aovs": "alpha"})"), {"render.aovs", "expected an array"});
  expect_error(scene(cam, R"({"resolution": [8, 8], "aovs": [3]})"), {"render.aovs", "\"3\" is not an AOV"});
}
