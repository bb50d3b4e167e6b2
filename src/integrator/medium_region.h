#pragma once
// Where a scene's media are: the coarse grids learned over a fluorescent medium
// before a render (continuation guides, excitation photons) are laid over these.
#include <array>

#include "scene/scene.h"

namespace chlorovdb {

// Bounding box of the shapes that hold `medium` inside (their surfaces sampled
// on a 32 x 32 lattice); empty when the medium is not enclosed by any shape.
Bounds3 medium_region(const Scene& scene, int medium);

// The medium at p, read from the first surface a ray from p meets: the side of
// it the ray comes from.
int medium_at(const Scene& scene, const Vec3& p);

// Per-axis cell counts: `longest` along the longest axis, the others in proportion.
std::array<int, 3> cell_counts(const Bounds3& region, int longest);

}  // namespace chlorovdb
