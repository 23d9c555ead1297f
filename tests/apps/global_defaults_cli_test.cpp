// mcl --init global picks a particle count that works when -M is not given: KLD-sampling between
// --min-particles and --max-particles (AMCL's way); a given -M is used as it is.
#include <gtest/gtest.h>

#include <string>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;

TEST(GlobalDefaultsCli, AGlobalStartWithoutParticlesAdaptsItsCountByKld) {
  // A small --max-particles keeps the run short; it is the count a KLD global start begins with.
  const std::string run = "mcl --init global --runs 1 --duration 40 --max-particles 300 --json ";
  const auto adaptive = run_cli(run);
  ASSERT_EQ(adaptive.code, 0) << adaptive.err;
  const auto a = nlohmann::json::parse(adaptive.out);
  EXPECT_EQ(a["kld"], true) << adaptive.out;
  EXPECT_EQ(a["particles_peak"].get<double>(), 300.0) << adaptive.out;

  const auto fixed = run_cli(run + "-M 120");
  ASSERT_EQ(fixed.code, 0) << fixed.err;
  const auto f = nlohmann::json::parse(fixed.out);
  EXPECT_EQ(f["kld"], false) << fixed.out;
  EXPECT_EQ(f["particles_peak"].get<double>(), 120.0) << fixed.out;

  // A known start keeps the tracking default: no KLD without --kld.
  const auto known = run_cli("mcl --runs 1 -M 20 --json");
  ASSERT_EQ(known.code, 0) << known.err;
  EXPECT_FALSE(nlohmann::json::parse(known.out).contains("kld")) << known.out;
}

}  // namespace
