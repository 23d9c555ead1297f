// EKF-SLAM: the reference trace of data/slam-synthetic and the Kalman-filter identity.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/Dense>

#include "implicit/core/rng.hpp"
#include "implicit/slam/dataset.hpp"
#include "implicit/slam/ekf_slam.hpp"
#include "implicit/slam/slam_filter.hpp"
#include "slam/test_data.hpp"

namespace implicit::slam {
namespace {

// data/slam-synthetic/README.md: the reference EKF-SLAM (known association, Joseph form,
// augmentation at first sighting, zero initial pose covariance, Sigma1 with P = 0.5) on
// paper_le1_seed1. The same deterministic algorithm must agree to round-off accumulated over
// 5000 steps; 1e-6 m is the README's figure.
TEST(EkfSlam, MatchesReferenceTraceOnPaperSeed1) {
  const auto sc = load_carpark_scenario(repository_data_dir());
  const auto data = read_reference_csv(
      repository_data_dir() / "slam-synthetic" / "paper_le1_seed1.csv.gz", sc.landmarks);
  const auto ref =
      read_reference_trace(repository_data_dir() / "slam-synthetic" / "ekf_paper_le1_seed1.csv.gz");
  ASSERT_EQ(ref.size(), data.steps() + 1);
  SlamOptions opt;
  opt.method = SlamMethod::kEkf;
  auto ekf = make_slam_filter(opt, data.initial_pose);
  double max_pos = 0.0, max_head = 0.0;
  for (std::size_t n = 1; n <= data.steps(); ++n) {
    ekf->step(n, data.control(n), data.observations(n));
    const Pose x = ekf->pose().mean;
    max_pos = std::max(max_pos, (x.head<2>() - ref[n].head<2>()).norm());
    max_head = std::max(max_head, std::abs(x(2) - ref[n](2)));
  }
  RecordProperty("max_position_difference_m", fmt::format("{:.3e}", max_pos));
  EXPECT_LT(max_pos, 1e-6);
  EXPECT_LT(max_head, 1e-6);
  EXPECT_EQ(ekf->stats().new_landmarks, 15u);
}

TEST(SyntheticData, PaperTruthReproducesReferenceFiles) {
  const auto sc = load_carpark_scenario(repository_data_dir());
  ASSERT_EQ(sc.controls.size(), 5000u);
  ASSERT_EQ(sc.landmarks.size(), 15u);
  const auto ref = read_reference_csv(
      repository_data_dir() / "slam-synthetic" / "paper_le1_seed1.csv.gz", sc.landmarks);
  SyntheticConfig cfg;
  const auto d = generate_synthetic(sc, cfg, 7);
  ASSERT_EQ(d.truth.size(), ref.truth.size());
  double worst = 0.0;
  for (std::size_t n = 0; n < d.truth.size(); ++n)
    worst = std::max(worst, (d.truth[n] - ref.truth[n]).cwiseAbs().maxCoeff());
  EXPECT_LT(worst, 1e-9);
  // Every step has one detection of a visible landmark (the route always sees a beacon), and
  // the detection is close to the noise-free measurement (|noise| < 6 sd).
  std::size_t with = 0;
  const robot::RangeBearingSensor s;
  for (std::size_t n = 1; n <= d.steps(); ++n) {
    for (const auto& o : d.observations(n)) {
      ++with;
      const auto h = s.predict(d.truth[n], sc.landmarks[static_cast<std::size_t>(o.landmark)]);
      const auto e = robot::RangeBearingSensor::residual(h, o.z);
      EXPECT_LT(std::abs(e(0)), 6.0 * std::sqrt(0.05));
      EXPECT_LT(std::abs(e(1)), 6.0 * std::sqrt(0.05 * kPi / 180.0));
    }
  }
  EXPECT_EQ(with, ref.observation_count());
}

TEST(SyntheticData, LaserEveryKthStepAndDeterminism) {
  const auto sc = load_carpark_scenario(repository_data_dir());
  SyntheticConfig cfg;
  cfg.laser_every = 8;
  const auto a = generate_synthetic(sc, cfg, 3);
  const auto b = generate_synthetic(sc, cfg, 3);
  for (std::size_t n = 1; n <= a.steps(); ++n) {
    if (n % 8 != 0) {
      EXPECT_TRUE(a.observations(n).empty());
    }
    ASSERT_EQ(a.observations(n).size(), b.observations(n).size());
    for (std::size_t i = 0; i < a.observations(n).size(); ++i)
      EXPECT_EQ(a.observations(n)[i].z, b.observations(n)[i].z);
  }
  EXPECT_EQ(a.observation_count(), 625u);
}

// Linear-Gaussian landmark problem: pose moves by x_n = A x_{n-1} + c_n + w (Q), the sensor sees
// z = Cx x + Cm m + v (R) with Cm invertible, and a landmark is initialised at first sighting
// from m = Cm^{-1}(z - Cx x) (exact under a flat landmark prior). The EKF core must equal the
// exact posterior, computed here in batch by least squares over all poses and landmarks.
TEST(EkfSlamCore, EqualsExactPosteriorOnLinearGaussianProblem) {
  const int steps = 12, nl = 3;
  Mat<3> A;
  A << 1.0, 0.0, 0.1, 0.0, 1.0, -0.05, 0.0, 0.0, 1.0;
  Mat<3> Q;
  Q << 0.04, 0.01, 0.0, 0.01, 0.03, 0.002, 0.0, 0.002, 0.01;
  Mat23 Cx;
  Cx << -1.0, 0.0, 0.3, 0.0, -1.0, -0.2;
  Mat<2> Cm;
  Cm << 1.0, 0.1, -0.2, 0.9;
  Mat<2> R;
  R << 0.02, 0.005, 0.005, 0.03;
  const Vec<3> x0(1.0, -2.0, 0.3);
  std::vector<Vec<3>> c(steps + 1);
  std::vector<Vec<2>> m = {Vec<2>(5, 1), Vec<2>(-3, 4), Vec<2>(2, -6)};
  std::vector<int> seen(steps + 1);
  std::vector<Vec<2>> z(steps + 1);
  Rng rng({99, 0, 0, purpose::kData});
  Vec<3> x = x0;
  for (int n = 1; n <= steps; ++n) {
    c[n] = Vec<3>(0.5, 0.2 * n, -0.01);
    x = A * x + c[n] + Q.llt().matrixL() * rng.normal_vector<3>();
    seen[n] = n % nl;
    z[n] = Cx * x + Cm * m[static_cast<std::size_t>(seen[n])] +
           R.llt().matrixL() * rng.normal_vector<2>();
  }
  EkfSlamCore ekf(x0, Mat<3>::Zero());
  std::vector<int> slot(nl, -1), order;
  for (int n = 1; n <= steps; ++n) {
    ekf.predict(A * ekf.pose() + c[n], A, Q);
    const int id = seen[n];
    if (slot[id] < 0) {
      const Eigen::PartialPivLU<Mat<2>> lu(Cm);
      const Mat<2> gz = lu.solve(Mat<2>::Identity());
      slot[id] = ekf.augment(gz * (z[n] - Cx * ekf.pose()), -gz * Cx, gz * R * gz.transpose());
      order.push_back(id);
    } else {
      const Vec<2> nu = z[n] - Cx * ekf.pose() - Cm * ekf.landmark(slot[id]);
      ASSERT_TRUE(ekf.update(slot[id], nu, Cx, Cm, R));
    }
  }
  // Batch: unknowns y = (x_1..x_N, m_order...), residuals whitened by Q and R; x_0 is known.
  const int dim = 3 * steps + 2 * nl;
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(dim, dim);
  Eigen::VectorXd eta = Eigen::VectorXd::Zero(dim);
  const Mat<3> qi = Q.llt().solve(Mat<3>::Identity());
  const Mat<2> ri = R.llt().solve(Mat<2>::Identity());
  auto lm_index = [&](int id) {
    const auto it = std::find(order.begin(), order.end(), id);
    return 3 * steps + 2 * static_cast<int>(it - order.begin());
  };
  for (int n = 1; n <= steps; ++n) {
    // motion residual x_n - A x_{n-1} - c_n
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, dim);
    Vec<3> rhs = c[n];
    J.block<3, 3>(0, 3 * (n - 1)) = Mat<3>::Identity();
    if (n > 1)
      J.block<3, 3>(0, 3 * (n - 2)) = -A;
    else
      rhs += A * x0;
    info += J.transpose() * qi * J;
    eta += J.transpose() * qi * rhs;
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2, dim);
    H.block<2, 3>(0, 3 * (n - 1)) = Cx;
    H.block<2, 2>(0, lm_index(seen[n])) = Cm;
    info += H.transpose() * ri * H;
    eta += H.transpose() * ri * z[n];
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(info);
  const Eigen::VectorXd mean = llt.solve(eta);
  const Eigen::MatrixXd cov = llt.solve(Eigen::MatrixXd::Identity(dim, dim));
  // Compare the last pose and the landmarks (the filter's marginal).
  std::vector<int> idx;
  for (int k = 0; k < 3; ++k) idx.push_back(3 * (steps - 1) + k);
  for (int k = 0; k < 2 * nl; ++k) idx.push_back(3 * steps + k);
  for (std::size_t a = 0; a < idx.size(); ++a) {
    EXPECT_NEAR(ekf.mean()(static_cast<Eigen::Index>(a)), mean(idx[a]), 1e-10) << a;
    for (std::size_t b = 0; b < idx.size(); ++b)
      EXPECT_NEAR(ekf.covariance()(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)),
                  cov(idx[a], idx[b]), 1e-10)
          << a << "," << b;
  }
  // Covariance stays symmetric positive definite.
  EXPECT_EQ((ekf.covariance() - ekf.covariance().transpose()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(ekf.covariance()).info(), Eigen::Success);
}

}  // namespace
}  // namespace implicit::slam
