// Trajectories: the TUM, KITTI and relations readers (fixtures, round trips, every malformed line
// named by file and line), association by time, Umeyama alignment undoing a known transform,
// APE, RPE and the relation metric against hand-computed values, and the statistics' bootstrap
// intervals against the normal theory.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/robot/trajectory.hpp"
#include "implicit/robot/trajectory_metrics.hpp"

namespace implicit::robot {
namespace {

using ::testing::HasSubstr;

constexpr double kTrajTestDeg = kPi / 180.0;

Trajectory traj_test_planar(const std::vector<double>& times, const std::vector<Pose>& poses) {
  return Trajectory::from_se2(times, poses);
}

/// The message of the ParseError `f` throws ("" and a failure when it throws none).
template <typename F>
std::string traj_test_parse_error(F&& f) {
  try {
    f();
  } catch (const ParseError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a ParseError";
  return {};
}

TEST(TrajectoryFiles, TumFixtureWithCommentsAndBlankLines) {
  const Trajectory t = parse_tum(
      "# t x y z qx qy qz qw\n\n1.0 1 2 3 0 0 0 1\n  \t\n"
      "1.5\t4 5 6 0 0 0.7071067811865476 0.7071067811865476  # a quarter turn\r\n",
      "a.tum");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.times[1], 1.5);
  EXPECT_EQ(t.poses[1].translation, Vec<3>(4, 5, 6));
  EXPECT_NEAR(t.poses[1].rotation_angle(), kPi / 2, 1e-15);
  EXPECT_NEAR(t.poses[1].rotation.z(), std::sqrt(0.5), 1e-16);
}

TEST(TrajectoryFiles, TumWriteThenReadGivesTheSameDoubles) {
  const auto dir =
      std::filesystem::temp_directory_path() / fmt::format("implicit-trajectory-{}", ::getpid());
  std::filesystem::create_directories(dir);
  Trajectory t =
      traj_test_planar({0.1, 0.2, 1.0 / 3.0},
                       {Pose(1e-17, -2.5, 0.3), Pose(1.0 / 7.0, 2e8, -3.0), Pose(0, 0, 1e-9)});
  t.poses[2].translation(2) = -1.0 / 3.0;
  write_tum(dir / "t.tum", t);
  const Trajectory back = read_tum(dir / "t.tum");
  ASSERT_EQ(back.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back.times[i], t.times[i]);
    EXPECT_EQ(back.poses[i].translation, t.poses[i].translation);
    EXPECT_EQ(back.poses[i].rotation.coeffs(), t.poses[i].rotation.coeffs());
  }
  const std::string missing = traj_test_parse_error([&] { read_tum(dir / "none.tum"); });
  EXPECT_THAT(missing, HasSubstr("none.tum"));
  std::filesystem::remove_all(dir);
}

TEST(TrajectoryFiles, TumMalformedLinesNameFileAndLine) {
  const auto err = [](const std::string& text) {
    return traj_test_parse_error([&] { parse_tum(text, "bad.tum"); });
  };
  const std::string good = "0 0 0 0 0 0 0 1\n";
  EXPECT_THAT(err(good + "1 0 0 0 0 0 1\n"),
              HasSubstr("bad.tum:2: expected 8 fields (t x y z qx qy qz qw), got 7"));
  EXPECT_THAT(err(good + "# c\n1 0 0 0 0 0 0 1 9\n"), HasSubstr("bad.tum:3: expected 8 fields"));
  EXPECT_THAT(err(good + "1 0 abc 0 0 0 0 1\n"),
              HasSubstr("bad.tum:2: field 3 (y): expected a finite number, got 'abc'"));
  EXPECT_THAT(err(good + "1 0 0 0 0 0 0 nan\n"), HasSubstr("bad.tum:2: field 8 (qw)"));
  EXPECT_THAT(err(good + "1 0 0 inf 0 0 0 1\n"), HasSubstr("bad.tum:2: field 4 (z)"));
  EXPECT_THAT(err(good + "1 0 0 0 0 0 0 1.01\n"),
              HasSubstr("bad.tum:2: expected a unit quaternion"));
  EXPECT_THAT(err(good + "1 0 0 0 0 0 0 0\n"), HasSubstr("got norm 0"));
  EXPECT_THAT(err(good + "0 0 0 0 0 0 0 1\n"),
              HasSubstr("bad.tum:2: expected a time after 0 (times must increase), got 0"));
  EXPECT_THAT(err("# only a comment\n\n"), HasSubstr("bad.tum:1: expected at least one pose"));
  EXPECT_THAT(err(std::string("0 0 0 0 0 0 0 1\x1b\n")), HasSubstr("got '1\\x1b'"));
  // Within 1e-3 of norm 1 the quaternion is accepted and normalised.
  const Trajectory t = parse_tum("0 0 0 0 0 0 0 1.0009\n", "ok.tum");
  EXPECT_NEAR(t.poses[0].rotation.norm(), 1.0, 1e-15);
}

TEST(TrajectoryFiles, KittiFramesAndRotationChecks) {
  const Trajectory t = parse_kitti(
      "1 0 0 0 0 1 0 0 0 0 1 0\n"
      "0 -1 0 1.5 1 0 0 2.5 0 0 1 -0.5\n",
      "00.txt");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.times[0], 0.0);
  EXPECT_EQ(t.times[1], 1.0);
  EXPECT_EQ(t.poses[1].translation, Vec<3>(1.5, 2.5, -0.5));
  EXPECT_NEAR((t.poses[1].matrix().topLeftCorner<3, 3>() -
               Eigen::Matrix3d(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ())))
                  .norm(),
              0, 1e-15);
  const auto err = [](const std::string& text) {
    return traj_test_parse_error([&] { parse_kitti(text, "k.txt"); });
  };
  EXPECT_THAT(err("1 0 0 0 0 1 0 0 0 0 1\n"), HasSubstr("k.txt:1: expected 12 fields"));
  EXPECT_THAT(err("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1.1 0\n"),
              HasSubstr("k.txt:2: expected a rotation"));
  EXPECT_THAT(err("1 0 0 0 0 1 0 0 0 0 -1 0\n"), HasSubstr("det R = -1"));
  EXPECT_THAT(err("1 0 0 0 0 1 0 x 0 0 1 0\n"), HasSubstr("k.txt:1: field 8 (t2)"));
}

TEST(TrajectoryFiles, RelationsFixtureAndMalformedLines) {
  const auto rel = parse_relations("# t1 t2 x y z roll pitch yaw\n2 1 1 0 0 0 0 0.5\n", "r.rel");
  ASSERT_EQ(rel.size(), 1u);
  EXPECT_EQ(rel[0].t1, 2.0);
  EXPECT_EQ(rel[0].line, 2u);
  EXPECT_NEAR(rel[0].delta.rotation_angle(), 0.5, 1e-15);
  // R = Rz(yaw) Ry(pitch) Rx(roll): a pitch of 90 degrees takes x to -z.
  const auto p = Pose3::from_rpy(Vec<3>::Zero(), 0.3, kPi / 2, 0.0);
  EXPECT_NEAR((p.rotation * Vec<3>(1, 0, 0) - Vec<3>(0, 0, -1)).norm(), 0, 1e-15);
  const auto err = [](const std::string& text) {
    return traj_test_parse_error([&] { parse_relations(text, "r.rel"); });
  };
  EXPECT_THAT(err("1 2 0 0 0 0 0\n"), HasSubstr("r.rel:1: expected 8 fields"));
  EXPECT_THAT(err("\n3 3 0 0 0 0 0 0\n"), HasSubstr("r.rel:2: expected two different times"));
  EXPECT_THAT(err("1 2 0 0 0 0 0 -nan\n"), HasSubstr("field 8 (yaw)"));
  EXPECT_THAT(err(""), HasSubstr("r.rel:1: expected at least one relation"));
}

TEST(TrajectoryAssociation, MissingAndJitteredStampsOneToOne) {
  std::vector<double> ref_t, est_t;
  std::vector<Pose> ref_p, est_p;
  for (int i = 0; i < 10; ++i) {
    ref_t.push_back(i);
    ref_p.emplace_back(i, 0, 0);
    if (i == 3 || i == 7) continue;  // no estimate there
    // Jitter within 0.01 s; the estimate's clock runs 100 s behind (offset 100).
    est_t.push_back(i - 100 + (i % 2 == 0 ? 0.004 : -0.009));
    est_p.emplace_back(i, 1, 0);
  }
  est_t.push_back(9.5 - 100);  // between two reference times, further than 0.01 from either
  est_p.emplace_back(0, 0, 0);
  const auto ref = traj_test_planar(ref_t, ref_p), est = traj_test_planar(est_t, est_p);
  const PosePairs pairs = associate(ref, est, {.max_diff = 0.01, .offset = 100});
  ASSERT_EQ(pairs.size(), 8u);
  const std::vector<std::size_t> expected_ref{0, 1, 2, 4, 5, 6, 8, 9};
  EXPECT_EQ(pairs.ref_index, expected_ref);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    EXPECT_EQ(pairs.est_index[k], k);
    EXPECT_EQ(pairs.est[k].translation(0), pairs.ref[k].translation(0));
  }
  // Without the offset nothing matches, and the message says where each trajectory lies.
  try {
    associate(ref, est, {.max_diff = 0.01});
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("got none (reference 10 poses in [0, 9] s"));
  }
  // One estimate near two reference times goes to the closer one, whichever comes first.
  const auto three = traj_test_planar({0, 1, 2}, {Pose::Zero(), Pose::Zero(), Pose::Zero()});
  const auto late = associate(three, traj_test_planar({1.9}, {Pose::Zero()}), {.max_diff = 1});
  ASSERT_EQ(late.size(), 1u);
  EXPECT_EQ(late.ref_index[0], 2u);
  const auto early = associate(three, traj_test_planar({1.05}, {Pose::Zero()}), {.max_diff = 1});
  ASSERT_EQ(early.size(), 1u);
  EXPECT_EQ(early.ref_index[0], 1u);
  EXPECT_THROW(associate(three, three, {.max_diff = -1}), InvalidArgument);
  EXPECT_THROW(associate(three, three, {.offset = NAN}), InvalidArgument);
}

/// Positions spread in 3-D, the estimate; the reference is scale * R * est + t.
std::vector<Vec<3>> traj_test_points() {
  std::vector<Vec<3>> p;
  for (int i = 0; i < 12; ++i)
    p.emplace_back(3.0 * std::cos(0.7 * i) + 0.1 * i, 2.0 * std::sin(1.3 * i), 0.5 * i - 2.0);
  return p;
}

TEST(TrajectoryAlignment, UndoesAKnownTransformExactly) {
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(2.1, Vec<3>(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  const Vec<3> t(10.0, -4.0, 2.5);
  const std::vector<Vec<3>> est = traj_test_points();
  for (const double scale : {1.0, 0.37}) {
    std::vector<Vec<3>> ref;
    for (const auto& x : est) ref.push_back(scale * r * x + t);
    const AlignmentKind kind = scale == 1.0 ? AlignmentKind::kSe3 : AlignmentKind::kSim3;
    const Alignment a = align_umeyama(est, ref, kind);
    EXPECT_NEAR((a.rotation - r).cwiseAbs().maxCoeff(), 0, 1e-12) << to_string(kind);
    EXPECT_NEAR((a.translation - t).cwiseAbs().maxCoeff(), 0, 1e-12);
    EXPECT_NEAR(a.scale, scale, 1e-12);
    EXPECT_NEAR(a.rotation.determinant(), 1.0, 1e-12);
  }
  // SE(3) keeps scale 1 when the data were scaled; Sim(3) finds it.
  std::vector<Vec<3>> half;
  for (const auto& x : est) half.push_back(0.5 * x);
  EXPECT_EQ(align_umeyama(est, half, AlignmentKind::kSe3).scale, 1.0);
  EXPECT_NEAR(align_umeyama(est, half, AlignmentKind::kSim3).scale, 0.5, 1e-12);
  // SE(2): a turn about z and a 3-D shift, recovered exactly from positions at several heights.
  const Eigen::Matrix3d rz = Eigen::AngleAxisd(-2.9, Vec<3>::UnitZ()).toRotationMatrix();
  std::vector<Vec<3>> ref2;
  for (const auto& x : est) ref2.push_back(rz * x + t);
  const Alignment a2 = align_umeyama(est, ref2, AlignmentKind::kSe2);
  EXPECT_NEAR((a2.rotation - rz).cwiseAbs().maxCoeff(), 0, 1e-12);
  EXPECT_NEAR((a2.translation - t).cwiseAbs().maxCoeff(), 0, 1e-12);
  EXPECT_NEAR(a2.rotation_angle(), 2.9, 1e-12);
  EXPECT_EQ(align_umeyama(est, ref2, AlignmentKind::kNone).rotation, Eigen::Matrix3d::Identity());
}

TEST(TrajectoryAlignment, MirrorImageGivesARotationAndDegenerateSetsAreRefused) {
  // The best orthogonal map onto a mirror image is the reflection; Umeyama's S keeps R proper.
  const std::vector<Vec<3>> est = traj_test_points();
  std::vector<Vec<3>> mirrored;
  for (const auto& x : est) mirrored.emplace_back(x(0), x(1), -x(2));
  const Alignment a = align_umeyama(est, mirrored, AlignmentKind::kSe3);
  EXPECT_NEAR(a.rotation.determinant(), 1.0, 1e-12);
  EXPECT_NEAR((a.rotation.transpose() * a.rotation - Eigen::Matrix3d::Identity()).norm(), 0, 1e-12);
  // On a line: the turn about the line is not fixed (3-D), but a planar turn is.
  std::vector<Vec<3>> line;
  for (int i = 0; i < 5; ++i) line.emplace_back(i, 2.0 * i, 0.0);
  try {
    align_umeyama(line, line, AlignmentKind::kSe3);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("not all on one line"));
  }
  EXPECT_NEAR(align_umeyama(line, line, AlignmentKind::kSe2).rotation_angle(), 0, 1e-12);
  const std::vector<Vec<3>> same(4, Vec<3>(1, 2, 3));
  EXPECT_THROW(align_umeyama(same, same, AlignmentKind::kSe2), InvalidArgument);
  EXPECT_THROW(align_umeyama(line, same, AlignmentKind::kSe3), InvalidArgument);  // sizes
  EXPECT_THROW(align_umeyama({line[0], line[1]}, {line[0], line[1]}, AlignmentKind::kSim3),
               InvalidArgument);
  // Squares of 1e300 overflow: refused, not aligned with NaN.
  const std::vector<Vec<3>> huge{Vec<3>(1e300, 0, 0), Vec<3>(-1e300, 1e300, 0),
                                 Vec<3>(0, 0, 1e300)};
  EXPECT_THROW(align_umeyama(huge, huge, AlignmentKind::kSe3), InvalidArgument);
  EXPECT_THROW(alignment_kind_from_string("se4"), InvalidArgument);
}

TEST(TrajectoryErrorsByHand, AbsolutePoseErrorAndItsStatistics) {
  const auto ref = traj_test_planar({0, 1, 2}, {Pose(0, 0, 0), Pose(1, 0, 0), Pose(2, 0, 0)});
  const auto est = traj_test_planar(
      {0, 1, 2}, {Pose(0, 0.1, 0), Pose(1, -0.2, 10 * kTrajTestDeg), Pose(2, 0, 0)});
  const TrajectoryErrors e = absolute_pose_error(associate(ref, est));
  EXPECT_NEAR(e.translation[0], 0.1, 1e-15);
  EXPECT_NEAR(e.translation[1], 0.2, 1e-15);
  EXPECT_EQ(e.translation[2], 0.0);
  EXPECT_NEAR(e.rotation_deg[1], 10.0, 1e-12);
  // |E - I|_F with |R - I|_F^2 = 6 - 2 tr R = 4 (1 - cos a).
  EXPECT_NEAR(e.full[1], std::sqrt(4 * (1 - std::cos(10 * kTrajTestDeg)) + 0.04), 1e-15);
  const ErrorStatistics s = error_statistics(e.translation, {.resamples = 0});
  EXPECT_NEAR(s.mean, 0.1, 1e-15);
  EXPECT_NEAR(s.median, 0.1, 1e-15);
  EXPECT_NEAR(s.rmse, std::sqrt(0.05 / 3), 1e-15);
  EXPECT_NEAR(s.std, std::sqrt(0.02 / 3), 1e-15);
  EXPECT_EQ(s.min, 0.0);
  EXPECT_EQ(s.max, e.translation[1]);
  EXPECT_TRUE(std::isnan(s.mean_lo));
  EXPECT_EQ(error_statistics({1, 4, 2, 3}).median, 2.5);
  EXPECT_THROW(error_statistics({}), InvalidArgument);
  EXPECT_THROW(error_statistics({1.0, NAN}), InvalidArgument);
  EXPECT_THROW(error_statistics({1.0}, {.level = 1.0}), InvalidArgument);
}

TEST(TrajectoryErrorsByHand, RelativePoseErrorInFramesAndMetres) {
  const auto ref =
      traj_test_planar({0, 1, 2, 3}, {Pose(0, 0, 0), Pose(1, 0, 0), Pose(2, 0, 0), Pose(3, 0, 0)});
  const auto est = traj_test_planar(
      {0, 1, 2, 3}, {Pose(0, 0, 0), Pose(1.1, 0, kPi / 2), Pose(2.1, 0, 0), Pose(3.3, 0, 0)});
  const PosePairs pairs = associate(ref, est);
  const TrajectoryErrors e = relative_pose_error(pairs, {}, {.delta = 1});
  ASSERT_EQ(e.translation.size(), 3u);
  // 0 -> 1: E = (0.1, 0) and a quarter turn. 1 -> 2: the estimate moves (0, -1) in its own
  // frame and turns back, against (1, 0): E = (-1, -1), a quarter turn.
  EXPECT_NEAR(e.translation[0], 0.1, 1e-15);
  EXPECT_NEAR(e.rotation_deg[0], 90.0, 1e-12);
  EXPECT_NEAR(e.translation[1], std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(e.rotation_deg[1], 90.0, 1e-12);
  EXPECT_NEAR(e.translation[2], 0.2, 1e-15);
  EXPECT_NEAR(e.rotation_deg[2], 0.0, 1e-12);
  // delta 2: (0, 2) alone, or (0, 2) and (1, 3) with all pairs.
  const auto two = relative_pose_error(pairs, {}, {.delta = 2});
  EXPECT_EQ(two.first, std::vector<std::size_t>{0});
  const auto all = relative_pose_error(pairs, {}, {.delta = 2, .all_pairs = true});
  EXPECT_EQ(all.second, (std::vector<std::size_t>{2, 3}));
  EXPECT_NEAR(all.translation[0], 0.1, 1e-15);
  // 1 -> 3: the estimate moves (0, -2.2) in its frame, the reference (2, 0): E = (-2, -2.2).
  EXPECT_NEAR(all.translation[1], std::sqrt(4.0 + 2.2 * 2.2), 1e-14);
  // Metres along the reference: steps of 0.5 m, delta 1 m.
  std::vector<double> t5;
  std::vector<Pose> p5;
  for (int i = 0; i < 5; ++i) {
    t5.push_back(i);
    p5.emplace_back(0.5 * i, 0, 0);
  }
  const PosePairs line = associate(traj_test_planar(t5, p5), traj_test_planar(t5, p5));
  const auto m = relative_pose_error(line, {}, {.delta = 1, .unit = DeltaUnit::kMetres});
  EXPECT_EQ(m.first, (std::vector<std::size_t>{0, 2}));
  EXPECT_EQ(m.second, (std::vector<std::size_t>{2, 4}));
  const auto m_all =
      relative_pose_error(line, {}, {.delta = 1, .unit = DeltaUnit::kMetres, .all_pairs = true});
  EXPECT_EQ(m_all.first, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_THROW(relative_pose_error(pairs, {}, {.delta = 1.5}), InvalidArgument);
  EXPECT_THROW(relative_pose_error(pairs, {}, {.delta = 4}), InvalidArgument);
  EXPECT_THROW(relative_pose_error(pairs, {}, {.delta = 0, .unit = DeltaUnit::kMetres}),
               InvalidArgument);
}

TEST(TrajectoryErrorsByHand, RelationMetric) {
  const auto est =
      traj_test_planar({0, 1, 2}, {Pose(0, 0, 0), Pose(1, 0, kPi / 2), Pose(1, 1, kPi / 2)});
  std::vector<Relation> rel{
      {0.0, 1.0, Pose3::from_se2(Pose(1, 0, kPi / 2)), 1},  // exact
      {1.0, 2.0, Pose3::from_se2(Pose(1.1, 0, 0.1)), 2},    // 0.1 m and 0.1 rad off
      {1.0, 5.0, Pose3::from_se2(Pose(1, 0, 0)), 3},        // no pose at t = 5
  };
  const RelationErrors r = relation_errors(est, rel, {.max_diff = 0.01});
  ASSERT_EQ(r.used, (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(r.skipped, 1u);
  EXPECT_NEAR(r.translation[0], 0, 1e-15);
  EXPECT_NEAR(r.translation[1], 0.1, 1e-14);
  EXPECT_NEAR(r.rotation_deg[1], 0.1 / kTrajTestDeg, 1e-12);
  EXPECT_NEAR(r.translation_mean, 0.05, 1e-15);
  EXPECT_NEAR(r.translation_sq_mean, 0.005, 1e-15);
  EXPECT_NEAR(r.rotation_mean_deg, 0.05 / kTrajTestDeg, 1e-12);
  EXPECT_NEAR(r.rotation_sq_mean_deg, 0.5 * std::pow(0.1 / kTrajTestDeg, 2), 1e-10);
  // The offset moves the estimate's clock: with +10 s no relation finds its poses.
  EXPECT_THROW(relation_errors(est, rel, {.offset = 10}), InvalidArgument);
}

TEST(TrajectoryStatistics, BootstrapIntervalIsDeterministicAndHasNormalWidth) {
  // 400 errors, deterministic and spread: the bootstrap interval of the mean is about
  // mean +- 1.96 std / sqrt(n). With 2000 resamples each end is off by about 0.06 standard
  // errors of the mean (sqrt(p (1 - p) / B) / phi(1.96)), so the width is within 2.5% of the
  // normal one; 8% is over three times that.
  std::vector<double> v;
  for (int i = 0; i < 400; ++i) v.push_back(std::fmod(0.6180339887 * i, 1.0) * (1 + i % 3));
  const StatisticsOptions o{.seed = 7, .resamples = 2000};
  const ErrorStatistics s = error_statistics(v, o);
  const ErrorStatistics again = error_statistics(v, o);
  EXPECT_EQ(s.mean_lo, again.mean_lo);
  EXPECT_EQ(s.rmse_hi, again.rmse_hi);
  const double normal_width = 2 * 1.959964 * s.std / std::sqrt(400.0);
  EXPECT_NEAR((s.mean_hi - s.mean_lo) / normal_width, 1.0, 0.08);
  EXPECT_NEAR(0.5 * (s.mean_hi + s.mean_lo), s.mean, 0.1 * normal_width);
  EXPECT_LT(s.rmse_lo, s.rmse);
  EXPECT_GT(s.rmse_hi, s.rmse);
  EXPECT_NE(error_statistics(v, {.seed = 8, .resamples = 2000}).mean_lo, s.mean_lo);
}

}  // namespace
}  // namespace implicit::robot
