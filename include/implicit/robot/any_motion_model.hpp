#pragma once
// Any motion model as one value type, for estimators that are compiled once and choose the robot
// at run time (the SLAM filters: slam::SlamOptions::model).
//
//   robot::AnyMotionModel motion = robot::UnicycleModel();   // or UteModel, or your own
//   Pose f = motion.with_dt(0.2).predict(x, u);
//   if (const auto* u = motion.target<robot::UnicycleModel>()) ...   // the model as its type
//
// The model must satisfy LinearizableMotionModel: MotionModel, with_dt() (steps of any length)
// and jacobian_state() (EKF-SLAM linearises the motion). Each call costs one indirect call;
// with_dt() allocates once, so call it once per step, not per particle.

#include <concepts>
#include <memory>
#include <utility>

#include "implicit/robot/models.hpp"

namespace implicit::robot {

/// A motion model that steps any length and gives J_f_x (3x3).
template <typename M>
concept LinearizableMotionModel = VariableStepMotionModel<M> &&
    requires(const M& m, const Pose& x, const Control& u) {
  { m.jacobian_state(x, u) } -> std::convertible_to<Mat3>;
};

class AnyMotionModel {
 public:
  // The self-exclusion comes first: checking LinearizableMotionModel<AnyMotionModel> here would
  // recurse into this constructor (clang++ 14 crashes on it).
  template <typename M>
  requires(!std::same_as<std::remove_cvref_t<M>, AnyMotionModel> && LinearizableMotionModel<M>)
      AnyMotionModel(M model)  // NOLINT: implicit on purpose, any model converts
      : self_(std::make_shared<const Holder<M>>(std::move(model))) {}

  double dt() const { return self_->dt(); }
  AnyMotionModel with_dt(double dt) const { return self_->with_dt(dt); }
  Pose predict(const Pose& x, const Control& u) const { return self_->predict(x, u); }
  Mat3 process_covariance(const Pose& x, const Control& u) const {
    return self_->process_covariance(x, u);
  }
  Mat3 jacobian_state(const Pose& x, const Control& u) const { return self_->jacobian_state(x, u); }

  /// The model held, as its own type M; nullptr when it holds another type. Estimators use it to
  /// run a known model without the indirect calls (experiments/motion_models.hpp).
  template <typename M>
  const M* target() const {
    const auto* holder = dynamic_cast<const Holder<M>*>(self_.get());
    return holder ? &holder->model : nullptr;
  }

 private:
  struct Interface {
    virtual ~Interface() = default;
    virtual double dt() const = 0;
    virtual AnyMotionModel with_dt(double dt) const = 0;
    virtual Pose predict(const Pose& x, const Control& u) const = 0;
    virtual Mat3 process_covariance(const Pose& x, const Control& u) const = 0;
    virtual Mat3 jacobian_state(const Pose& x, const Control& u) const = 0;
  };
  template <typename M>
  struct Holder final : Interface {
    explicit Holder(M m) : model(std::move(m)) {}
    double dt() const override { return model.dt(); }
    AnyMotionModel with_dt(double dt) const override { return AnyMotionModel(model.with_dt(dt)); }
    Pose predict(const Pose& x, const Control& u) const override { return model.predict(x, u); }
    Mat3 process_covariance(const Pose& x, const Control& u) const override {
      return model.process_covariance(x, u);
    }
    Mat3 jacobian_state(const Pose& x, const Control& u) const override {
      return model.jacobian_state(x, u);
    }
    M model;
  };
  std::shared_ptr<const Interface> self_;
};

static_assert(LinearizableMotionModel<AnyMotionModel>);

}  // namespace implicit::robot
