// Online landmark SLAM on your own data: every estimator of the library on one data set, with
// maximum-likelihood data association (no landmark ids needed), stepped one control at a time as
// a robot would.
//
//   example_landmark_slam                 a synthetic Car Park data set (seed 1)
//   example_landmark_slam my_run.log.gz   a plain-text robot log (docs/formats.md)
//
// The estimators share one interface (SlamFilter): step(n, control, detections), then pose() and
// map() whenever you need them. Only SlamOptions changes between methods. With the truth in the
// data, evaluate() reports the path error and the map error after the best rigid alignment (SLAM
// fixes the map only up to a rotation and shift, so the raw landmark error mostly measures that).
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>

#include "implicit/slam/dataset.hpp"
#include "implicit/slam/evaluate.hpp"
#include "implicit/slam/slam_filter.hpp"

namespace slam = implicit::slam;

int main(int argc, char** argv) try {
  const slam::SyntheticConfig paper_like;  // noise-free truth, one detection per step
  const slam::SlamDataset data =
      argc > 1 ? slam::read_slam_log(argv[1])
               : slam::generate_synthetic(slam::load_carpark_scenario(slam::default_data_dir()),
                                          paper_like, /*seed=*/1);
  data.validate();  // NaN, negative ranges, inconsistent steps: an error naming the step
  std::printf("%s: %zu steps, %zu detections\n", data.name.c_str(), data.steps(),
              data.observation_count());

  for (slam::SlamMethod method :
       {slam::SlamMethod::kEkf, slam::SlamMethod::kFastSlam1, slam::SlamMethod::kFastSlam2,
        slam::SlamMethod::kImplicit, slam::SlamMethod::kImplicitRb}) {
    slam::SlamOptions opt;
    opt.method = method;
    opt.association = slam::Association::kMaximumLikelihood;
    opt.particles = 100;
    opt.seed = 7;  // same seed, same numbers, whatever the thread count

    // What run_filter() does, written out: the loop a robot runs online.
    slam::SlamRun run;
    auto filter = slam::make_slam_filter(opt, data.initial_pose);
    run.path.push_back(data.initial_pose);
    run.path_cov.push_back(implicit::Mat<3>::Zero());
    for (std::size_t n = 1; n <= data.steps(); ++n) {
      filter->step(n, data.control(n), data.observations(n));
      const slam::PoseEstimate now = filter->pose();  // mean and covariance after step n
      run.path.push_back(now.mean);
      run.path_cov.push_back(now.cov);
    }
    run.map = filter->map();
    run.stats = filter->stats();

    std::printf("\n%-12s final pose (%.2f m, %.2f m, %.3f rad), %zu landmarks, ESS/M %.2f\n",
                std::string(slam::to_string(method)).c_str(), run.path.back()(0),
                run.path.back()(1), run.path.back()(2), run.map.landmarks.size(),
                run.stats.mean_ess_fraction());
    if (data.truth.empty()) continue;
    const slam::SlamMetrics m = slam::evaluate(data, run);
    std::printf("%-12s path error %.2f %% (aligned %.2f %%), map shape %.3f m\n", "",
                m.error_percent, m.error_aligned_percent, m.map_shape_m);
  }
} catch (const std::exception& e) {
  std::fprintf(stderr, "example_landmark_slam: %s\n", e.what());
  return 1;
}
