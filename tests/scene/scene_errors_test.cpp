// Bad scene files give one clear error naming the file, the key path and the
// value (and the nearest valid key or name), never a crash or a silent default.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "scene/scene_loader.h"

using namespace chlorovdb;

namespace {

std::filesystem::path write(const std::string& name, const std::string& text) {
  const auto path = test::scratch_dir("scene_tests") / name;
  std::ofstream(path) << text;
  return path;
}

// Loads `json` and returns the error message ("" if it loaded).
std::string load_error(const std::string& json, const std::string& name = "bad.json") {
  try {
    load_scene(write(name, json));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

const std::string kCamera = R"("camera": {"position": [0, 0, 3], "look_at": [0, 0, 0]})";

std::string scene_with(const std::string& body) { return "{" + kCamera + (body.empty() ? "" : ", " + body) + "}"; }

}  // namespace

TEST(SceneErrors, MinimalSceneLoads) { EXPECT_EQ(load_error(scene_with("")), ""); }

TEST(SceneErrors, MalformedJsonNamesFileLineAndColumn) {
  const std::string msg = load_error("{\n  \"camera\": {\"position\": [0, 0, 3],,}\n}", "malformed.json");
  EXPECT_NE(msg.find("malformed.json:2:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("malformed JSON"), std::string::npos) << msg;
}

TEST(SceneErrors, NumberBeyondDoubleRangeIsAnInputError) {
  // Fuzzing finding F10: nlohmann's out_of_range escaped as an internal error.
  const std::string msg = load_error(scene_with(R"("render": {"spp": 1e400})"), "overflow.json");
  EXPECT_NE(msg.find("overflow.json"), std::string::npos) << msg;
  EXPECT_NE(msg.find("1e400"), std::string::npos) << msg;
}

TEST(SceneErrors, DevicesAreNotSceneFiles) {
  // Fuzzing finding F1: /dev/zero was read forever.
  try {
    load_scene("/dev/zero");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
  }
}

TEST(SceneErrors, SpectrumValuesWhoseIntegralOverflowsAreRefused) {
  // Fuzzing finding F3: an emission table near FLT_MAX integrated to inf and was
  // then reported as "zero". Now the table itself is refused, naming the key.
  const std::string msg = load_error(scene_with(
      R"("pigments": {"p": {"extinction": 1e4, "quantum_yield": 0.5,
                            "emission": {"table": {"lambda": [300, 800], "value": [3e38, 3e38]}}}})"));
  EXPECT_NE(msg.find("pigments.p.emission"), std::string::npos) << msg;
  EXPECT_NE(msg.find("overflow"), std::string::npos) << msg;
}

TEST(SceneErrors, UnknownKeySuggestsTheNearestValidOne) {
  const std::string msg = load_error(R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fvo": 30}})");
  EXPECT_NE(msg.find("bad.json"), std::string::npos) << msg;
  EXPECT_NE(msg.find("camera.fvo"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean \"fov\""), std::string::npos) << msg;
}

TEST(SceneErrors, UnknownTopLevelKey) {
  const std::string msg = load_error(scene_with(R"("light": [])"));
  EXPECT_NE(msg.find("light"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean \"lights\""), std::string::npos) << msg;
}

TEST(SceneErrors, WrongTypeNamesKeyAndValue) {
  const std::string msg = load_error(scene_with(R"("render": {"spp": "many"})"));
  EXPECT_NE(msg.find("render.spp = \"many\""), std::string::npos) << msg;
  EXPECT_NE(msg.find("integer"), std::string::npos) << msg;
}

TEST(SceneErrors, QuantumYieldOutsideUnitInterval) {
  const std::string msg =
      load_error(scene_with(R"("pigments": {"chl": {"extinction": "chlorophyll_a", "quantum_yield": 1.5}})"));
  EXPECT_NE(msg.find("pigments.chl.quantum_yield = 1.5"), std::string::npos) << msg;
  EXPECT_NE(msg.find("[0, 1]"), std::string::npos) << msg;
}

TEST(SceneErrors, NegativeConcentration) {
  const std::string msg = load_error(scene_with(R"(
    "pigments": {"chl": {"extinction": "chlorophyll_a"}},
    "media": {"m": {"pigments": [{"pigment": "chl", "concentration": -5}]}})"));
  EXPECT_NE(msg.find("concentration = -5"), std::string::npos) << msg;
}

TEST(SceneErrors, UnknownMaterialNameSuggestsNearest) {
  const std::string msg = load_error(scene_with(R"(
    "materials": {"white": {"type": "diffuse"}},
    "shapes": [{"type": "sphere", "radius": 1, "material": "whit"}])"));
  EXPECT_NE(msg.find("shapes[0].material = \"whit\""), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean \"white\""), std::string::npos) << msg;
}

TEST(SceneErrors, UnknownEnumValue) {
  const std::string msg = load_error(scene_with(R"("render": {"fluorescence": "drect"})"));
  EXPECT_NE(msg.find("render.fluorescence"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean \"direct\""), std::string::npos) << msg;
}

TEST(SceneErrors, UnknownExcitationSamplingOrQuantumYieldMode) {
  std::string msg = load_error(scene_with(R"("render": {"excitation_sampling": "unifrom"})"), "bad_sampling.json");
  EXPECT_NE(msg.find("bad_sampling.json"), std::string::npos) << msg;
  EXPECT_NE(msg.find("render.excitation_sampling"), std::string::npos) << msg;
  EXPECT_NE(msg.find("unifrom"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean \"uniform\""), std::string::npos) << msg;
  msg = load_error(scene_with(R"("render": {"quantum_yield_mode": "rulette"})"), "bad_qmode.json");
  EXPECT_NE(msg.find("bad_qmode.json"), std::string::npos) << msg;
  EXPECT_NE(msg.find("render.quantum_yield_mode"), std::string::npos) << msg;
  EXPECT_NE(msg.find("rulette"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean \"roulette\""), std::string::npos) << msg;
  EXPECT_EQ(load_error(scene_with(R"("render": {"excitation_sampling": "uniform", "quantum_yield_mode": "roulette"})")),
            "");
}

TEST(SceneErrors, UnknownContinuationDirections) {
  const std::string msg = load_error(scene_with(R"("render": {"continuation_directions": "guidded"})"), "bad_guide.json");
  EXPECT_NE(msg.find("bad_guide.json"), std::string::npos) << msg;
  EXPECT_NE(msg.find("render.continuation_directions"), std::string::npos) << msg;
  EXPECT_NE(msg.find("guidded"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean \"guided\""), std::string::npos) << msg;
  EXPECT_EQ(load_error(scene_with(R"("render": {"continuation_directions": "guided"})")), "");
}

TEST(SceneErrors, MissingMeshFileNamesTheFile) {
  const std::string msg = load_error(scene_with(R"(
    "materials": {"white": {"type": "diffuse"}},
    "shapes": [{"type": "mesh", "file": "no_such_mesh.obj", "material": "white"}])"));
  EXPECT_NE(msg.find("no_such_mesh.obj"), std::string::npos) << msg;
}

TEST(SceneErrors, MissingGridFileNamesTheFile) {
  const std::string msg = load_error(scene_with(R"(
    "pigments": {"chl": {"extinction": "chlorophyll_a"}},
    "media": {"m": {"pigments": [{"pigment": "chl", "grid": {"file": "missing.vdb", "name": "c"}}]}})"));
  EXPECT_NE(msg.find("missing.vdb"), std::string::npos) << msg;
}

TEST(SceneErrors, UnsortedSpectrumTableNamesScenePath) {
  const auto csv = write("unsorted.csv", "wavelength_nm,value\n500,1\n400,2\n600,3\n");
  const std::string msg = load_error(scene_with(
      R"("lights": [{"type": "point", "position": [0, 1, 0], "spectrum": ")" + csv.string() + R"("}])"));
  EXPECT_NE(msg.find("unsorted.csv"), std::string::npos) << msg;
  EXPECT_NE(msg.find("lights[0].spectrum"), std::string::npos) << msg;
}

TEST(SceneErrors, OpenMeshCannotHoldAMedium) {
  const std::string msg = load_error(scene_with(R"(
    "materials": {"b": {"type": "interface"}},
    "media": {"m": {"solvent": "water"}},
    "shapes": [{"type": "quad", "corner": [0, 0, 0], "edge_u": [1, 0, 0], "edge_v": [0, 1, 0],
                "material": "b", "inside": "m"}])"));
  EXPECT_NE(msg.find("shapes[0].inside"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not closed"), std::string::npos) << msg;
}

TEST(SceneErrors, CommandLineOverrideIsChecked) {
  SceneOverrides o;
  o.fluorescence = "ful";
  try {
    load_scene(write("ok.json", scene_with("")), o);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--fluorescence = ful"), std::string::npos) << e.what();
  }
}

TEST(SceneErrors, UnknownCameraWavelengths) {
  const std::string msg = load_error(scene_with(R"("render": {"camera_wavelengths": "visable"})"), "bad_lanes.json");
  EXPECT_NE(msg.find("bad_lanes.json"), std::string::npos) << msg;
  EXPECT_NE(msg.find("render.camera_wavelengths"), std::string::npos) << msg;
  EXPECT_NE(msg.find("visable"), std::string::npos) << msg;
  EXPECT_EQ(load_error(scene_with(R"("render": {"camera_wavelengths": "visible"})")), "");
}
