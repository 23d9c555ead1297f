#pragma once
// The likelihood-field laser model (Thrun, Burgard & Fox, Probabilistic Robotics §6.4), as one
// observation model per scan (observation_model.hpp), with nav2 AMCL's parameter names.
//
// Each used beam i ends, at robot pose x, at the world point p_i(x) = x ⊕ e_i, where e_i is
// the beam's end point in the robot frame (mount ⊕ (r cos b, r sin b)). With d_i(x) the distance
// from p_i(x) to the nearest occupied cell (distance_field.hpp, capped at max_distance):
//
//   log p(scan | x) = sum_i log( z_hit N(d_i; 0, sigma_hit^2) + z_rand / z_max )
//
// a proper density per beam: N is the normalised Gaussian and z_rand / z_max the uniform density
// over [0, z_max). Which beams are used follows nav2: readings at or above the maximum range (no
// return) and below the minimum range are skipped, and at most max_beams beams are taken, evenly
// spaced over the scan. A beam ending outside the map sees max_distance.
//
// For the implicit proposal the model also gives -log p and its gradient in the pose, and a
// Gauss-Newton matrix: per beam w_i (J^T grad d_i)(J^T grad d_i)^T with w_i = gamma_i /
// sigma_hit^2, gamma_i = the hit component's share of the beam's density. It is positive
// semi-definite, so with the motion prior the pose objective's matrix is positive definite;
// the weights of the implicit proposal are exact with any such matrix.
//
// BeamAggregation::kCubedSum is nav2/Beluga's 1 + sum_i p_i^3 with the unnormalised
// p_i = z_hit exp(-d_i^2 / 2 sigma^2) + z_rand / z_max, for parity runs only: it is not a
// likelihood, so the bootstrap proposal can use it and the implicit proposal refuses it.
//
//   auto field = std::make_shared<const DistanceField>(grid, 2.0);
//   LikelihoodFieldModel model(field, LikelihoodFieldParams{}, LaserMount{});
//   LikelihoodFieldModel::Prepared beams = model.prepare(scan);  // once per scan
//   double log_p = model.log_likelihood(beams, pose);             // per particle

#include <cmath>
#include <memory>
#include <string_view>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/core/types.hpp"
#include "implicit/robot/distance_field.hpp"
#include "implicit/robot/laser_scan.hpp"
#include "implicit/robot/types.hpp"

namespace implicit::robot {

enum class BeamAggregation {
  kProduct,   ///< the likelihood: the product of the beams' densities
  kCubedSum,  ///< nav2/Beluga's 1 + sum p^3 (parity only; not a likelihood)
};

/// nav2 AMCL's names and defaults, where nav2 has the parameter.
struct LikelihoodFieldParams {
  double z_hit = 0.5;
  double z_rand = 0.5;
  double sigma_hit = 0.2;  ///< [m]
  /// laser_likelihood_max_dist [m]: distances are capped here (the field's own cap is used
  /// when it is smaller).
  double laser_likelihood_max_dist = 2.0;
  int max_beams = 60;
  double laser_max_range = -1.0;  ///< [m]; <= 0: the scan's range_max
  double laser_min_range = -1.0;  ///< [m]; <= 0: the scan's range_min
  Interpolation interpolation = Interpolation::kBicubic;
  BeamAggregation aggregation = BeamAggregation::kProduct;

  /// Throws InvalidArgument naming the parameter.
  void validate() const;
};

/// The log density of a beam ending in each cell of a distance field, for one maximum range:
/// what nearest-cell interpolation reads instead of evaluating the density per beam. Laid out
/// as the field's padded cells; as float, whose rounding (2^-24 of |log(z_rand / z_max)| at
/// most) is below that of the distances the field stores as float.
struct CellLogDensity {
  double z_max = 0.0;
  std::vector<float> cells;
  float outside = 0.0f;         ///< beyond the field's cells: the density at the capped distance
  const void* owner = nullptr;  ///< the model that built it (shared with its copies)
};

/// The end points of one scan's used beams in the robot frame, and the constants of its beam
/// density: computed once per scan, shared by every particle.
struct PreparedScan {
  std::vector<Vec<2>> end_points;     ///< e_i in the robot frame [m]
  double z_max = 0.0;                 ///< the maximum range this scan was read with [m]
  double log_hit_scale = 0.0;         ///< log(z_hit / (sqrt(2 pi) sigma_hit))
  double rand_density = 0.0;          ///< z_rand / z_max
  std::size_t skipped_no_return = 0;  ///< readings at or above the maximum range
  std::size_t skipped_short = 0;      ///< readings below the minimum range
  /// Nearest-cell interpolation with the product aggregation: the beam density per cell, shared
  /// by every scan with this z_max (null otherwise).
  std::shared_ptr<const CellLogDensity> cell_log_density;
  std::size_t size() const { return end_points.size(); }
};

class LikelihoodFieldModel {
 public:
  using Observation = LaserScan;
  using Prepared = PreparedScan;

  /// Throws InvalidArgument for a null field or invalid parameters.
  LikelihoodFieldModel(std::shared_ptr<const DistanceField> field, const LikelihoodFieldParams& p,
                       const LaserMount& mount = {});

  const LikelihoodFieldParams& params() const { return p_; }
  const LaserMount& mount() const { return mount_; }
  const DistanceField& field() const { return *field_; }
  /// Whether negative_log_likelihood() is defined (kProduct with a differentiable
  /// interpolation); the implicit proposal refuses a model without it.
  bool differentiable() const {
    return p_.aggregation == BeamAggregation::kProduct &&
           p_.interpolation != Interpolation::kNearest;
  }
  /// Why not differentiable(), for the error message ("" when it is).
  std::string_view why_not_differentiable() const;

  /// The beams this model uses of `scan` (validated; `where` names it in errors). A scan
  /// whose every reading is "no return" gives no beams: its likelihood is 1.
  PreparedScan prepare(const LaserScan& scan, std::string_view where = "laser scan") const;

  /// log p(scan | x) (kCubedSum: log(1 + sum p^3)).
  double log_likelihood(const PreparedScan& z, const Pose& x) const;

  /// -log p(scan | x); if gradient / gauss_newton are not null, ADDS d(-log p)/dx and the
  /// Gauss-Newton matrix described above. kProduct only (differentiable()).
  double negative_log_likelihood(const PreparedScan& z, const Pose& x, Vec<3>* gradient,
                                 Mat3* gauss_newton) const;

  /// The log density of one beam whose end point is `distance` from the nearest obstacle.
  double beam_log_density(const PreparedScan& z, double distance) const {
    const double h = z.log_hit_scale - 0.5 * distance * distance * inv_var_;
    // e^h + c with c > 0 is correct to rounding whichever term dominates, and so is its log;
    // without the uniform term (z_rand = 0) e^h would underflow far from the walls.
    return z.rand_density > 0.0 ? std::log(std::exp(h) + z.rand_density) : h;
  }

 private:
  struct CellTables;  // the CellLogDensity of each z_max seen, shared by copies of the model

  std::shared_ptr<const CellLogDensity> cell_log_density(double z_max) const;
  template <Interpolation Mode>
  double interpolated_log_likelihood(const PreparedScan& z, const Pose& x) const;
  template <Interpolation Mode>
  double interpolated_negative_log_likelihood(const PreparedScan& z, const Pose& x,
                                              Vec<3>* gradient, Mat3* gauss_newton) const;
  double nearest_log_likelihood(const PreparedScan& z, const Pose& x) const;
  double cubed_sum_log_likelihood(const PreparedScan& z, const Pose& x) const;

  std::shared_ptr<const DistanceField> field_;
  LikelihoodFieldParams p_;
  LaserMount mount_;
  double max_distance_ = 0.0;  ///< min(laser_likelihood_max_dist, field's cap)
  double inv_var_ = 0.0;       ///< 1 / sigma_hit^2
  std::shared_ptr<CellTables> cell_tables_;
};

}  // namespace implicit::robot
