#include "sdf_tracker/camera/sensor_model.h"

#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

std::vector<std::string> DepthNoiseModel::validate() const {
  Violations v;
  v.requirePositive("sigma_at_z0_m", sigma_at_z0_m);
  v.requireNonNegative("quadratic_m_per_m2", quadratic_m_per_m2);
  v.requireNonNegative("z0_m", z0_m);
  v.requirePositive("reference_depth_m", reference_depth_m);
  return v.list();
}

}  // namespace sdf_tracker
