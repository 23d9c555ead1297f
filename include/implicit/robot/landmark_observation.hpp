#pragma once
// Range-bearing detections of point landmarks as an observation model (observation_model.hpp):
// the landmark filter is Monte Carlo localization (filter/monte_carlo_localization.hpp) with this
// model, as the laser filter is with the likelihood field.
//
//   LandmarkObservation model(RangeBearingSensor(), map, AssociationOptions{});
//   LandmarkDetections<RangeBearingSensor> d = model.prepare(detections, "log.txt:12");
//   double lp = model.log_likelihood(d, pose);        // log p(z | x), association included
//
// An observation is the detections of one step (std::span of LabelledMeasurement); prepare()
// checks them and gives the view every particle reads: the model and the detections (no copy).
// log p(z | x) associates each unlabelled detection at x by maximum likelihood with S = Sigma2 and
// a chi-square gate (data_association.hpp, spec §3.9): a Gaussian term per associated detection,
// log p0 (the clutter density on the gate boundary) per dropped one when clutter is on. It is the
// bootstrap's weight, the target of global starts and the likelihood of recovery's sources.
//
// The implicit proposal does not minimise this function: it associates once per particle at its
// prediction f with the predictive covariance H Sigma1 H^T + Sigma2 (associate() with a pose
// covariance) and minimises the smooth objective of that association (filter/mcl_objective.hpp,
// with a written-out range-bearing path). negative_log_likelihood() is the seam's generic form
// (association at x, Gauss-Newton matrix), exact where the association does not change.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>

#include "implicit/core/error.hpp"
#include "implicit/core/gaussian.hpp"
#include "implicit/core/types.hpp"
#include "implicit/robot/data_association.hpp"
#include "implicit/robot/landmark_map.hpp"
#include "implicit/robot/models.hpp"
#include "implicit/robot/observation_model.hpp"

namespace implicit::robot {

/// A detection with its landmark, if known (index into the map; -1 = associate).
struct LabelledMeasurement {
  Measurement z;
  int landmark = -1;
};

/// The default gate on a labelled detection's d^2 against the filter's prediction: the 2-dof
/// chi-square quantile at 1 - 1e-6, -2 log(1e-6). A detection consistent with the model fails it
/// once in a million steps; one from another landmark or a broken sensor fails it at once.
inline constexpr double kLabelGateDefault = 27.631021115928547;

struct AssociationOptions {
  double gate = kChiSquare2Dof99;  ///< chi-square gate on d^2 (2 dof, 99 %)
  /// Labelled detections: chi-square gate on d^2 against the predicted pose distribution
  /// (LandmarkObservation::gate); 0 = every label is trusted.
  double label_gate = kLabelGateDefault;
  bool clutter = true;      ///< dropped detections contribute p0
  double min_range = 0.05;  ///< [m] landmarks closer than this are not candidates
};

/// Detections per step that a filter accepts (the Car Park has at most 6): the implicit
/// proposal's objective holds its terms in fixed-size arrays, with no allocation per particle.
inline constexpr int kMaxDetectionsPerStep = 32;

template <LandmarkSensor Sensor>
class LandmarkObservation;

/// One step's detections as every particle reads them, with the model that reads them (valid
/// while both live). Global localization's multi-start takes it as it is.
template <LandmarkSensor Sensor>
struct LandmarkDetections {
  using SensorType = Sensor;
  const LandmarkObservation<Sensor>* model = nullptr;
  std::span<const LabelledMeasurement> z;
  std::size_t size() const { return z.size(); }
};

template <LandmarkSensor Sensor>
class LandmarkObservation {
 public:
  using SensorType = Sensor;
  using Observation = std::span<const LabelledMeasurement>;
  using Prepared = LandmarkDetections<Sensor>;
  using GateKept = std::vector<LabelledMeasurement>;

  /// Throws InvalidArgument for a gate that is not positive or a sensor covariance that is not
  /// symmetric positive definite.
  LandmarkObservation(Sensor sensor, LandmarkMap map, AssociationOptions association = {})
      : sensor_(std::move(sensor)), map_(std::move(map)), association_(association) {
    require(association_.gate > 0, "particle filter: expected a positive gate, got {}",
            association_.gate);
    require(association_.label_gate >= 0 && std::isfinite(association_.label_gate),
            "particle filter: expected a label gate >= 0 (0: off), got {}",
            association_.label_gate);
    const Mat2& noise = sensor_.noise_covariance();
    Eigen::LLT<Mat2> llt(noise);
    require(llt.info() == Eigen::Success && noise.allFinite(),
            "particle filter: expected a symmetric positive definite sensor covariance, got "
            "[[{}, {}], [{}, {}]]",
            noise(0, 0), noise(0, 1), noise(1, 0), noise(1, 1));
    noise_information_ = llt.solve(Mat2::Identity());
    log_det_noise_ = 2.0 * std::log(llt.matrixL()(0, 0) * llt.matrixL()(1, 1));
    log_clutter_ = clutter_log_density(association_.gate, noise);
  }

  const Sensor& sensor() const { return sensor_; }
  const LandmarkMap& map() const { return map_; }
  std::span<const Landmark> landmarks() const { return map_.positions(); }
  const AssociationOptions& association() const { return association_; }
  const Mat2& noise_information() const { return noise_information_; }  ///< Sigma2^-1
  double log_det_noise() const { return log_det_noise_; }               ///< log det Sigma2
  double log_clutter() const { return log_clutter_; }                   ///< log p0

  /// Checks the detections (at most kMaxDetectionsPerStep, finite, landmark indices below the
  /// map's size); `where` names them in the error.
  Prepared prepare(const Observation& z, std::string_view where = "detections") const {
    require(z.size() <= static_cast<std::size_t>(kMaxDetectionsPerStep),
            "{}: expected at most {} detections per step, got {}", where, kMaxDetectionsPerStep,
            z.size());
    for (const LabelledMeasurement& lz : z)
      require(lz.landmark < static_cast<int>(map_.size()) && lz.z.allFinite(),
              "{}: expected finite detections with a landmark index below {}, got ({}, {}) for "
              "landmark {}",
              where, map_.size(), lz.z(0), lz.z(1), lz.landmark);
    return view(z);
  }

  /// The detections as a Prepared without the checks (global starts read any number of them).
  Prepared view(std::span<const LabelledMeasurement> z) const { return Prepared{this, z}; }

  /// Leaves out the labelled detections that the predicted pose distribution N(mean, cov) could
  /// not produce: d^2 = e^T S^-1 e > label_gate with e = z - h(mean, landmark) and
  /// S = H cov H^T + Sigma2 (H: the Jacobian at the mean). Unlabelled detections are kept (their
  /// association has its own gate). Returns how many were left out; when that is not 0, `kept`
  /// holds the rest in their order. A spread-out cloud (a global start) gives a large S, so
  /// nothing is gated until the filter knows where it is.
  bool gate_needed(const Observation& z) const {
    return association_.label_gate > 0.0 &&
           std::any_of(z.begin(), z.end(),
                       [](const LabelledMeasurement& lz) { return lz.landmark >= 0; });
  }

  int gate(const Observation& z, const Pose& mean, const Mat3& cov, GateKept& kept) const {
    if (association_.label_gate <= 0.0) return 0;
    int left_out = 0;
    kept.clear();
    for (const LabelledMeasurement& lz : z) {
      if (lz.landmark >= 0 && lz.landmark < static_cast<int>(map_.size()) && lz.z.allFinite() &&
          label_distance2(mean, cov, lz) > association_.label_gate) {
        ++left_out;
        continue;
      }
      kept.push_back(lz);
    }
    return left_out;
  }

  /// d^2 of a labelled detection against N(mean, cov) (see gate); NaN if S is not SPD.
  double label_distance2(const Pose& mean, const Mat3& cov, const LabelledMeasurement& lz) const {
    Measurement h;
    Mat23 j;
    predict_with_jacobian(mean, map_.position(static_cast<std::size_t>(lz.landmark)), h, j);
    const Measurement e = sensor_.residual(h, lz.z);
    const Mat2 s = j * cov * j.transpose() + sensor_.noise_covariance();
    const Eigen::LLT<Mat2> llt(s);
    if (llt.info() != Eigen::Success) return std::numeric_limits<double>::quiet_NaN();
    return e.dot(llt.solve(e));
  }

  /// Maximum-likelihood association of z at pose x with innovation covariance
  /// H pose_cov H^T + Sigma2 (pose_cov = nullptr: Sigma2 alone); -1 when nothing is in the gate.
  int associate(const Pose& x, const Mat3* pose_cov, const Measurement& z) const {
    const Mat2& noise = sensor_.noise_covariance();
    const double min_r2 = association_.min_range * association_.min_range;
    // Exact range pre-gate (see RangeFirstSensor): skips most landmarks without an atan2.
    const double range_bound =
        association_.gate *
        (noise(0, 0) + (pose_cov ? (*pose_cov)(0, 0) + (*pose_cov)(1, 1) : 0.0));
    const double range_tol = std::sqrt(range_bound);
    const std::vector<Landmark>& map = map_.positions();
    return associate_max_likelihood(
               static_cast<int>(map.size()),
               [&](int i, Measurement& e, Mat2& s) {
                 const Landmark& m = map[static_cast<std::size_t>(i)];
                 if ((m - x.template head<2>()).squaredNorm() < min_r2) return false;
                 if constexpr (RangeFirstSensor<Sensor>) {
                   // |r - z_r| <= sqrt(bound), compared on squared distances (no square root).
                   const double d2 = (m - x.template head<2>()).squaredNorm();
                   const double lo = std::max(0.0, z(0) - range_tol), hi = z(0) + range_tol;
                   if (d2 < lo * lo || d2 > hi * hi) return false;
                 }
                 if (pose_cov) {
                   Measurement predicted;
                   Mat23 h;
                   predict_with_jacobian(x, m, predicted, h);
                   e = sensor_.residual(predicted, z);
                   const Eigen::Matrix<double, 2, 3> hp = h * (*pose_cov);
                   s.noalias() = hp * h.transpose();
                   s += noise;
                 } else {
                   e = sensor_.residual(sensor_.predict(x, m), z);
                   s = noise;
                 }
                 return true;
               },
               association_.gate)
        .index;
  }

  /// log p(z | x): labelled detections keep their landmark, the others are associated at x
  /// (S = Sigma2); a Gaussian term per associated detection, log p0 per dropped one when clutter
  /// is on. Adds the detections used and dropped to counts.used and counts.dropped.
  template <typename Counts>
  double log_likelihood(const Prepared& d, const Pose& x, Counts& counts) const {
    double log_w = 0.0;
    const double log_norm =
        -gaussian_log_normaliser(2, 0.5 * log_det_noise_);  // log N(0; 0, Sigma2)
    for (const LabelledMeasurement& lz : d.z) {
      const int k = lz.landmark >= 0 ? lz.landmark : associate(x, nullptr, lz.z);
      if (k < 0) {
        ++counts.dropped;
        if (association_.clutter) log_w += log_clutter_;
        continue;
      }
      ++counts.used;
      const Measurement e =
          sensor_.residual(sensor_.predict(x, map_.position(static_cast<std::size_t>(k))), lz.z);
      log_w += log_norm - 0.5 * e.dot(noise_information_ * e);
    }
    return log_w;
  }

  double log_likelihood(const Prepared& d, const Pose& x) const {
    ObservationCounts counts;
    return log_likelihood(d, x, counts);
  }

  /// The seam's derivatives: -log p(z | x) with the association at x, its gradient and the
  /// Gauss-Newton matrix sum J^T Sigma2^-1 J (ADDED to *gradient and *gauss_newton). Piecewise
  /// smooth: the association may change with x.
  double negative_log_likelihood(const Prepared& d, const Pose& x, Vec<3>* gradient,
                                 Mat3* gauss_newton) const {
    double value = 0.0;
    const double per_term = gaussian_log_normaliser(2, 0.5 * log_det_noise_);
    for (const LabelledMeasurement& lz : d.z) {
      const int k = lz.landmark >= 0 ? lz.landmark : associate(x, nullptr, lz.z);
      if (k < 0) {
        if (association_.clutter) value -= log_clutter_;
        continue;
      }
      Measurement h;
      Mat23 j;
      predict_with_jacobian(x, map_.position(static_cast<std::size_t>(k)), h, j);
      const Measurement e = sensor_.residual(h, lz.z);
      const Measurement s = noise_information_ * e;
      value += per_term + 0.5 * e.dot(s);
      if (gradient) *gradient += j.transpose() * s;
      if (gauss_newton) *gauss_newton += j.transpose() * noise_information_ * j;
    }
    return value;
  }
  bool differentiable() const { return true; }
  std::string_view why_not_differentiable() const { return {}; }

 private:
  void predict_with_jacobian(const Pose& x, const Landmark& m, Measurement& h, Mat23& j) const {
    if constexpr (LandmarkSensorWithFusedJacobian<Sensor>) {
      sensor_.predict_with_jacobian(x, m, h, j);
    } else {
      h = sensor_.predict(x, m);
      j = sensor_.jacobian_pose(x, m);
    }
  }

  Sensor sensor_;
  LandmarkMap map_;
  AssociationOptions association_;
  Mat2 noise_information_ = Mat2::Identity();
  double log_det_noise_ = 0.0;
  double log_clutter_ = 0.0;
};

/// Whether O is the landmark observation model (the implicit proposal's range-bearing path).
template <typename O>
inline constexpr bool is_landmark_observation_v = false;
template <typename S>
inline constexpr bool is_landmark_observation_v<LandmarkObservation<S>> = true;

static_assert(DifferentiableObservationModel<LandmarkObservation<RangeBearingSensor>>);
static_assert(CountingObservationModel<LandmarkObservation<RangeBearingSensor>>);
static_assert(PredictionGatedObservationModel<LandmarkObservation<RangeBearingSensor>>);

}  // namespace implicit::robot
