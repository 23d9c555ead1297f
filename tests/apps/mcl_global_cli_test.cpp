// `implicit mcl --init global` and `--kidnap-at` on the bundled car park: the JSON report's keys
// and their ranges, the particle counts with and without KLD-sampling, and the refused
// combinations (exit code 1, the message names the flag).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

#include "apps/cli_runner.hpp"

namespace implicit::test {
namespace {

using nlohmann::json;

json mcl_json(const std::string& args) {
  const auto r = run_cli("mcl " + args + " --json --threads 1");
  EXPECT_EQ(r.code, 0) << r.err;
  return r.code == 0 ? json::parse(r.out) : json::object();
}

// A rate of `runs` 0/1 outcomes: in [0, 1] and equal to the mean of the per-run outcomes.
void check_rate(const json& j, const std::string& key, int runs) {
  ASSERT_TRUE(j.contains(key)) << key;
  const double rate = j[key].get<double>();
  EXPECT_GE(rate, 0.0);
  EXPECT_LE(rate, 1.0);
  ASSERT_EQ(j["success_runs"].size(), static_cast<std::size_t>(runs));
  double sum = 0.0;
  for (const auto& s : j["success_runs"]) {
    const double v = s.get<double>();
    EXPECT_TRUE(v == 0.0 || v == 1.0) << v;
    sum += v;
  }
  EXPECT_DOUBLE_EQ(rate, sum / runs);
}

// A median of per-run times: null when no run converged, else a non-negative number.
void check_time(const json& j, const std::string& key) {
  ASSERT_TRUE(j.contains(key)) << key;
  if (!j[key].is_null()) {
    EXPECT_GE(j[key].get<double>(), 0.0);
  }
}

TEST(MclGlobalCli, GlobalStartReportsRatesTimesAndParticles) {
  // The first 45 s of the log: enough for both starts, and cheap under the sanitizers.
  const json j =
      mcl_json("--init global --method implicit -M 50 --runs 2 --duration 45 --start-span 5");
  ASSERT_FALSE(j.empty());
  EXPECT_EQ(j["init"], "global");
  EXPECT_EQ(j["source"], "mixture");  // implicit: the mixture over the minima
  check_rate(j, "global_success_rate", 2);
  check_time(j, "time_to_converge_s_median");
  EXPECT_EQ(j["time_to_converge_s_runs"].size(), 2u);
  EXPECT_EQ(j["particles_mean"].get<double>(), 50.0);  // fixed count without --kld
  EXPECT_EQ(j["particles_peak"].get<double>(), 50.0);
  const int fallbacks = j["uniform_fallback_starts"].get<int>();
  EXPECT_GE(fallbacks, 0);
  EXPECT_LE(fallbacks, 2);
  EXPECT_FALSE(j.contains("kidnap_recovery_rate"));
}

TEST(MclGlobalCli, KldKeepsTheParticleCountWithinItsBounds) {
  const json j = mcl_json(
      "--init global --method implicit -M 50 --runs 2 --duration 45 --start-span 5 --kld "
      "--min-particles 20 --max-particles 300");
  ASSERT_FALSE(j.empty());
  EXPECT_TRUE(j["kld"].get<bool>());
  EXPECT_LE(j["particles_peak"].get<double>(), 300.0);
  EXPECT_GE(j["particles_mean"].get<double>(), 20.0);
  EXPECT_LE(j["particles_mean"].get<double>(), j["particles_peak"].get<double>());
  check_rate(j, "global_success_rate", 2);
}

TEST(MclGlobalCli, KidnappingReportsRecovery) {
  const json j = mcl_json("--kidnap-at 60 --kidnap-skip 10 --method standard -M 100 --runs 2");
  ASSERT_FALSE(j.empty());
  EXPECT_EQ(j["init"], "known");
  EXPECT_EQ(j["kidnap_at_s"].get<double>(), 60.0);
  EXPECT_EQ(j["kidnap_skip_s"].get<double>(), 10.0);
  check_rate(j, "kidnap_recovery_rate", 2);
  check_time(j, "recovery_time_s_median");
  EXPECT_EQ(j["particles_mean"].get<double>(), 100.0);
  EXPECT_FALSE(j.contains("global_success_rate"));
}

TEST(MclGlobalCli, RefusedCombinationsNameTheFlag) {
  const auto kidnap = run_cli("mcl --init global --kidnap-at 5");
  EXPECT_EQ(kidnap.code, 1);
  EXPECT_NE(kidnap.err.find("--kidnap-at"), std::string::npos) << kidnap.err;
  const auto truth = run_cli("mcl --init global --truth reference");
  EXPECT_EQ(truth.code, 1);
  EXPECT_NE(truth.err.find("--truth"), std::string::npos) << truth.err;
}

}  // namespace
}  // namespace implicit::test
