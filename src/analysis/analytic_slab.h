#pragma once
// Analytic references: scenes whose exact image is known, for `chlorovdb
// converge --analytic NAME` and the convergence tests (docs/physics.md §7).
//
// A slab of pigment solution 0 <= z <= D, index-matched (interface box),
// lit at normal incidence by a distant light travelling along -z onto the face
// z = D, observed by an orthographic camera along the axis, so every pixel sees
// the same radiance. The pigment's extinction is flat over [eps_lo, eps_hi]
// (zero elsewhere, so it does not absorb where it emits), the solvent absorbs a
// flat zeta (1/m) and nothing scatters. With s the depth below the lit face,
// c(s) the concentration, mu_a(s, l') = 100 ln10 eps(l') c(s) and
// tau'(s) = zeta s + int_0^s mu_a(u, l') du, the fluorescence radiance is
//
//   L(l) = Q f(l) / (4 pi) int dl' (l'/l) E(l') int_0^D mu_a(s, l') e^{-tau'(s)} e^{-zeta d(s)} ds
//
// with d(s) = s on the lit (reflection) side and D - s on the far (transmission)
// side. For a uniform c this is docs/physics.md §7's closed form; for a linear c(s)
// (a grid medium: trilinear interpolation reproduces a linear field exactly)
// the inner integral is done by composite Simpson quadrature (relative error
// below 1e-9), the l' integral by the trapezoid rule on a 0.01 nm grid.
//
// A planar glass wall (slab_glass_wall*): a plate of relative IOR n, thickness
// glass_thickness, parallel to the lit face a gap above it (vacuum between
// plate and solution, so the solution's index is 1), the beam arriving at
// `incidence_deg` from the normal; the camera on the far face. The beam leaves
// the plate at its incidence angle theta, carrying the plate's incoherent
// Fresnel transmission T(theta) = (1-R)² / (1 - R²), and runs a
// path s / cos(theta) to depth s. The camera ray, after crossing the slab, is
// reflected back by the plate with R_eff = 2R/(1+R) (R at normal incidence) and
// sees the slab's lit-side emission a second time, attenuated by e^{-zeta D}.
// R is the unpolarised reflectance ½(R_s + R_p) at every face, as the renderer
// computes it (it does not track polarisation; tracking it would change T by
// +1 % at 60°).
//
// What is compared: the camera sees only fluorescence (nothing else reaches
// it), so the exact image has, in every pixel, total = fluorescence =
// RGB(XYZ(L)) with XYZ(L) = int cmf(l) L(l) dl / int ybar dl over 360-830 nm (the
// film's normalisation, spectra/color.h), and nonfluorescence = 0.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "io/image.h"
#include "scene/scene.h"
#include "spectra/color.h"

namespace chlorovdb {

struct SlabCase {
  std::string name = "slab";
  double D = 0.01;                   // thickness, m
  double c_lit = 20, c_far = 20;     // µM at the lit face (z = D) and the far face (z = 0); equal: homogeneous
  bool grid = false;                 // concentration from a .vdb grid (required when c_lit != c_far)
  double epsilon = 20000;            // L/mol/cm over [eps_lo, eps_hi]
  double eps_lo = 380, eps_hi = 480; // nm
  std::string light = "{\"gaussian\": [420, 8]}";  // spectral irradiance of the beam (scene spectrum syntax)
  double Q = 0.5;
  std::string emission = "{\"gaussian\": [650, 10]}";
  double zeta = 30;                  // solvent absorption, 1/m, flat
  bool reflection_side = true;       // camera on the lit face (else on the far face)
  int resolution = 16;               // square image, pixels
  int spp = 16;
  int wavelengths = 4;
  std::string fluorescence = "direct";
  std::string transmittance = "auto";
  double glass_ior = 0;              // > 0: a glass plate in front of the lit face (transmission side only)
  double glass_thickness = 0.002;    // m
  double incidence_deg = 0;          // the beam's angle to the slab's normal
  std::string excitation_through_glass = "connect";  // render.excitation_through_glass
};

// "slab" (docs/physics.md §7, homogeneous, lit side), "slab_transmission" (same, far
// side), "slab_linear" (grid medium, concentration linear in depth, lit side),
// "slab_glass_wall" (far side, behind a glass plate of IOR 1.5, normal incidence)
// and "slab_glass_wall_oblique" (the same, beam at 60°: past the critical angle
// of the plate's glass-air face).
std::vector<std::string> analytic_case_names();
// Throws InputError listing the names for an unknown one.
SlabCase analytic_case(std::string_view name);

// Writes NAME.json (and NAME.vdb for a grid case) into `dir`; returns the scene path.
std::filesystem::path write_slab_scene(const SlabCase& slab, const std::filesystem::path& dir);

// The exact fluorescence radiance L(lambda) of every pixel, W m^-2 sr^-1 nm^-1
// (the scene supplies the loaded spectra: extinction, normalised emission, light).
double slab_radiance(const SlabCase& slab, const Scene& scene, double lambda_nm);
// The plate's transmission at incidence theta (radians), relative IOR n, with
// every internal reflection, unpolarised at each face as the renderer assumes.
double plate_transmission(double n, double theta);
// Its CIE XYZ as the film computes it.
XYZ slab_xyz(const SlabCase& slab, const Scene& scene);
// The exact image in the renderer's layout (total, fluorescence, nonfluorescence; RGB
// in the scene's colour space) at the scene's resolution.
Image slab_reference_image(const SlabCase& slab, const Scene& scene);

}  // namespace chlorovdb
