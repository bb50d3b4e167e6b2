#pragma once
// The `pigments` and `media` sections of a scene file (docs/scene-format.md).
#include <map>
#include <memory>
#include <optional>
#include <string>
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

// Grids read once per (file, name) and shared by every field that names them.
using GridCache = std::map<std::pair<std::string, std::string>, std::shared_ptr<const VoxelGrid>>;

struct MediumDefinition {
  Medium medium;
  std::vector<FluorescentPigment> fluorescent;  // its pigments with Q > 0 (lights filled in later)
};
// `unit`: the scene's length unit in metres; grid transforms are in that unit.
MediumDefinition read_medium(ParamReader& params, const PigmentTable& pigments, GridCache& grids, float unit);

// True when anything in the medium scatters (molecules or particles).
bool can_scatter(const Medium& medium);
// World box of a grid medium's region; none for homogeneous media.
std::optional<Bounds3> medium_bounds(const Medium& medium);

}  // namespace chlorovdb
