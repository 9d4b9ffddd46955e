#pragma once

#include <algorithm>
#include <string>
#include <vector>

namespace sdf_tracker {

/// Axial depth noise of a structured-light sensor growing with depth, sigma(z) = a + b (z - z0)^2
/// (Kinect v1 fit of Nguyen, Izadi and Lovell, 3DIMPVT 2012). Measurements are weighted by their
/// inverse variance relative to one taken at reference_depth_m, capped at 1, as the paper suggests
/// ("reducing the influence of measurements made at greater distance").
struct DepthNoiseModel {
  double sigma_at_z0_m = 0.0012;
  double quadratic_m_per_m2 = 0.0019;
  double z0_m = 0.4;
  double reference_depth_m = 1.0;

  float sigma(float z_m) const {
    const float dz = z_m - static_cast<float>(z0_m);
    return static_cast<float>(sigma_at_z0_m) + static_cast<float>(quadratic_m_per_m2) * dz * dz;
  }
  float referenceSigma() const { return sigma(static_cast<float>(reference_depth_m)); }
  /// Inverse-variance weight relative to a measurement at reference_depth_m, in (0, 1]; hot loops
  /// pass referenceSigma() computed once.
  float weight(float z_m, float reference_sigma) const { return weightForSigmaRatio(sigma(z_m) / reference_sigma); }
  /// The same weight from sigma(z) / referenceSigma(), for callers that need the ratio too.
  static float weightForSigmaRatio(float sigma_ratio) { return std::min(1.0f, 1.0f / (sigma_ratio * sigma_ratio)); }

  std::vector<std::string> validate() const;
};

}  // namespace sdf_tracker
