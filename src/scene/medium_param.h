#pragma once
// The `pigments` and `media` sections of a scene file (docs/scene-format.md).
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "media/medium.h"
#include "scene/param_reader.h"
#include "scene/scene.h"

namespace chlorovdb {

struct PigmentDefinition {
  Pigment pigment;
  Redistribution redistribution = Redistribution::kasha_vavilov;
};
using PigmentTable = std::map<std::string, PigmentDefinition>;

PigmentTable read_pigments(ParamReader& top);

// Length units of scenes and grids ("m", "cm", "mm", "um") and their size in
// metres (0 for any other word).
extern const std::vector<std::string> kLengthUnits;
float metres_per_length_unit(const std::string& unit);

// Grids read once per (file, name, length unit given in the scene) and shared by every field that names them.
using GridCache =
    std::map<std::tuple<std::string, std::string, std::string>, std::shared_ptr<const VoxelGrid>>;

struct MediumDefinition {
  Medium medium;
  std::vector<FluorescentPigment> fluorescent;  // its pigments with Q > 0 (lights filled in later)
};
// Grid transforms are in each grid's own length unit (docs/scene-format.md), not the scene's.
MediumDefinition read_medium(ParamReader& params, const PigmentTable& pigments, GridCache& grids);

// True when anything in the medium scatters (molecules or particles).
bool can_scatter(const Medium& medium);
// World box of a grid medium's region; none for homogeneous media.
std::optional<Bounds3> medium_bounds(const Medium& medium);

}  // namespace chlorovdb
