#include "media/solvent.h"

#include <cmath>

namespace chlorovdb {

float water_rayleigh_sigma_s(float lambda_nm, float eta, float temperature_K) {
  // In double: lambda^4 in cm^4 is ~1e-17 and N ~ 6e23, beyond comfortable float range.
  constexpr double kPi = 3.14159265358979323846;
  constexpr double beta = 4.95e-11;  // cm^2 / dyne
  constexpr double R = 8.315e7;      // erg / (K mol)
  constexpr double N = 6.06e23;      // 1 / mol
  const double lambda_cm = double(lambda_nm) * 1e-7;
  const double n2 = double(eta) * double(eta);
  const double rayleigh_ratio = kPi * kPi / 18.0 * (beta * R * double(temperature_K) / (N * (lambda_cm * lambda_cm * lambda_cm * lambda_cm))) *
                                (n2 - 1.0) * (n2 - 1.0) * (n2 + 2.0) * (n2 + 2.0);  // 1/cm/sr
  // Unpolarised light scatters R90 (1 + cos^2 theta) per steradian; over the sphere that is (16 pi / 3) R90.
  const double sigma_s_per_cm = 16.0 * kPi / 3.0 * rayleigh_ratio;
  return float(sigma_s_per_cm * 100.0);                             // 1/cm -> 1/m
}

}  // namespace chlorovdb
