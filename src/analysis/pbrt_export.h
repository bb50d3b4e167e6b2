#pragma once
// A chlorovdb scene written in pbrt-v4's scene format, so images and speed can
// be cross-checked against pbrt-v4 (`chlorovdb export-pbrt`). pbrt-v4 has no
// fluorescence: a scene with a fluorescent pigment (Q > 0) is refused unless
// ignore_fluorescence, which exports its pigments as absorbers only (compare
// with `chlorovdb render --fluorescence off`).
//
// What maps how (docs/convergence.md, "Cross-checking against pbrt-v4"):
//  - camera: `Scale -1 1 1` then LookAt (pbrt-v4 is left-handed), perspective
//    fov on the shorter side as ours, orthographic screenwindow in metres;
//  - shapes: trianglemesh (our meshes in world space, CCW-outward winding as
//    pbrt's), sphere; MediumInterface "inside" "outside"; emitter-only shapes
//    pass through in both renderers (pbrt "interface" material);
//  - materials: diffuse reflectance spectrum, dielectric eta (float, or a
//    spectrum for a Sellmeier glass), interface;
//  - lights: point / spot / distant / infinite / diffuse area. pbrt-v4 divides
//    every light's spectrum by its photometric value, so "scale" is written as
//    our scale times the spectrum's luminance (spectra/color.h luminance) to
//    give the same radiometric emission;
//  - media: homogeneous -> sigma_a, sigma_s spectra (1/m) at 1 nm; grid media ->
//    "uniformgrid" with the voxel values dumped and sigma_a (sigma_s) per unit
//    grid value. pbrt-v4 has no Rayleigh phase function: molecular scattering
//    is exported with HG g = 0 (same mean cosine), noted in the file.
// Lengths are metres (render space = our world space).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "scene/scene.h"

namespace chlorovdb {

struct PbrtExportOptions {
  bool ignore_fluorescence = false;
  std::string film_filename = "chlorovdb.exr";  // pbrt's output image
  int spp = 0;                                 // 0: the scene's
  int64_t max_grid_voxels = int64_t(256) * 256 * 256;  // refuse to dump bigger grids
};

struct PbrtExport {
  std::string text;                   // the .pbrt file
  std::vector<std::string> warnings;  // approximations made (also written as comments)
};

// `scene` must be load_scene(scene_file): shapes are re-read from the file
// (GeometryScene keeps only Embree's copy) and matched to scene.shapes by
// position. Throws InputError naming the file for a fluorescent scene (unless
// ignored), a grid medium pbrt-v4 cannot express (two different grids), a
// grid over max_grid_voxels.
PbrtExport export_pbrt(const Scene& scene, const std::filesystem::path& scene_file, const PbrtExportOptions& options);

}  // namespace chlorovdb
