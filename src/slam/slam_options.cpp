// The SLAM methods and association modes by name, and the checks of SlamOptions.
#include <cmath>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/slam/slam_filter.hpp"

namespace implicit::slam {

std::string_view to_string(SlamMethod m) {
  switch (m) {
    case SlamMethod::kEkf:
      return "ekf";
    case SlamMethod::kFastSlam1:
      return "fastslam1";
    case SlamMethod::kFastSlam2:
      return "fastslam2";
    case SlamMethod::kImplicit:
      return "implicit";
    case SlamMethod::kImplicitRb:
      return "implicit-rb";
  }
  return "unknown";
}

SlamMethod parse_slam_method(std::string_view name) {
  for (SlamMethod m : {SlamMethod::kEkf, SlamMethod::kFastSlam1, SlamMethod::kFastSlam2,
                       SlamMethod::kImplicit, SlamMethod::kImplicitRb})
    if (to_string(m) == name) return m;
  throw InvalidArgument(fmt::format(
      "SLAM method: expected ekf|fastslam1|fastslam2|implicit|implicit-rb, got '{}'", name));
}

std::string_view to_string(Association a) { return a == Association::kKnown ? "known" : "ml"; }

Association parse_association(std::string_view name) {
  if (name == "known") return Association::kKnown;
  if (name == "ml") return Association::kMaximumLikelihood;
  throw InvalidArgument(fmt::format("SLAM association: expected known|ml, got '{}'", name));
}

void SlamOptions::validate() const {
  require(particles >= 1, "SLAM options: expected particles >= 1, got {}", particles);
  require(gate_chi2 > 0 && std::isfinite(gate_chi2),
          "SLAM options: expected a positive gate_chi2, got {}", gate_chi2);
  require(new_landmark_density > 0 && std::isfinite(new_landmark_density),
          "SLAM options: expected a positive new_landmark_density, got {}", new_landmark_density);
  require(resample_threshold >= 0 && resample_threshold <= 1,
          "SLAM options: expected resample_threshold in [0, 1], got {}", resample_threshold);
  require(min_range >= 0 && std::isfinite(min_range),
          "SLAM options: expected min_range >= 0, got {}", min_range);
  require(newton_max_iterations >= 1, "SLAM options: expected newton_max_iterations >= 1, got {}",
          newton_max_iterations);
  motion.validate();
}

}  // namespace implicit::slam
