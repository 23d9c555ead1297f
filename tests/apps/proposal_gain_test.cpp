// `implicit proposal-gain`: the JSON fields, the same numbers for any thread count, and the
// property the experiment exists to show, checked against its own standard errors.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"

namespace implicit::test {
namespace {

using nlohmann::json;

// One point per sweep at a small size: both sweeps, both proposals, well under a second.
const std::string kTiny =
    "proposal-gain --runs 3 --duration 8 --ratios 0.1,10 --dts 0.2 --seed 5 --json --quiet";

json gain_json(const std::string& args) {
  const auto r = run_cli(args);
  EXPECT_EQ(r.code, 0) << r.err;
  return json::parse(r.out);
}

json without_timing(json j) {
  // CPU and wall times differ between runs of the same computation; everything else may not.
  j.erase("seconds");
  j.erase("threads");
  for (auto& p : j["points"])
    for (const char* m : {"implicit", "standard", "diff"}) {
      p[m].erase("cpu_ms_per_step");
      p[m].erase("cpu_ms_per_step_se");
    }
  return j;
}

TEST(ProposalGain, TinyRunHasTheDocumentedFields) {
  const json j = gain_json(kTiny);
  for (const char* key : {"particles", "runs", "duration_s", "scan_period_s", "seed", "points",
                          "carpark_ratio", "seconds"})
    EXPECT_TRUE(j.contains(key)) << key;
  ASSERT_EQ(j["points"].size(), 3u);
  for (const auto& p : j["points"]) {
    for (const char* key : {"sweep", "dt", "range_sd", "bearing_sd", "ratio"})
      EXPECT_TRUE(p.contains(key)) << key;
    for (const char* m : {"implicit", "standard", "diff"})
      for (const char* k :
           {"ess", "ess_se", "rmse_m", "rmse_m_se", "cpu_ms_per_step", "cpu_ms_per_step_se"})
        EXPECT_TRUE(p[m].contains(k)) << m << "." << k;
    EXPECT_GT(p["implicit"]["ess"].get<double>(), 0.0);
    EXPECT_LE(p["implicit"]["ess"].get<double>(), 1.0);
  }
  EXPECT_EQ(j["points"][0]["sweep"], "ratio");
  EXPECT_EQ(j["points"][2]["sweep"], "dt");
  // The Car Park's configs: B's P = 0.1 gives a smaller per-step noise than A's P = 0.5.
  EXPECT_LT(j["carpark_ratio"]["B"].get<double>(), j["carpark_ratio"]["A"].get<double>());
}

TEST(ProposalGain, SameSeedSameJsonForOneAndTwoThreads) {
  EXPECT_EQ(without_timing(gain_json(kTiny + " --threads 1")),
            without_timing(gain_json(kTiny + " --threads 2")));
}

// At a noise ratio of 10 the bootstrap proposal puts almost no particle where the sensor says,
// the implicit one moves the last step's noise there: the paired ESS/M difference must exceed
// 4.5 of its standard errors (at a true gain of many SEs this fails with negligible
// probability; with no gain, a t-statistic above 4.5 with 7 degrees of freedom has p < 0.002).
// The bootstrap ESS/M must also fall from ratio 0.1 to 10 by more than 4.5 SEs of the
// difference of the two independent means.
TEST(ProposalGain, ImplicitGainsEssAtALargeNoiseRatio) {
  const json j = gain_json(
      "proposal-gain --runs 8 --duration 16 --ratios 0.1,10 --dts 0.1 --seed 11 --json "
      "--quiet");
  const auto& low = j["points"][0];
  const auto& high = j["points"][1];
  ASSERT_DOUBLE_EQ(high["ratio"].get<double>(), 10.0);
  const double gain = high["diff"]["ess"].get<double>();
  const double gain_se = high["diff"]["ess_se"].get<double>();
  EXPECT_GT(gain, 4.5 * gain_se) << gain << " ± " << gain_se;
  const double drop = low["standard"]["ess"].get<double>() - high["standard"]["ess"].get<double>();
  const double drop_se =
      std::hypot(low["standard"]["ess_se"].get<double>(), high["standard"]["ess_se"].get<double>());
  EXPECT_GT(drop, 4.5 * drop_se) << drop << " ± " << drop_se;
}

}  // namespace
}  // namespace implicit::test
