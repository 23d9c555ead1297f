// Named run records (run_record.hpp): the numbers that cross ranks and --resume files are derived
// from the field table, read back bit for bit, and refused with a reason when they are not the
// record's; the JSON names every field.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "experiments/control.hpp"
#include "experiments/landmark_mcl.hpp"
#include "experiments/landmark_slam.hpp"
#include "experiments/proposal_gain.hpp"
#include "experiments/run_record.hpp"
#include "experiments/slit_table.hpp"

namespace {

using implicit::experiments::column;
using implicit::experiments::NamedRecord;
using implicit::experiments::record_from_values;
using implicit::experiments::record_json;
using implicit::experiments::record_values;
using implicit::experiments::RecordField;
using implicit::experiments::RecordValues;

// Every kind of field a record may have.
struct Sample {
  double x = 0.0;
  bool flag = false;
  int count = 0;
  std::size_t size = 0;
  std::string name;
  std::vector<double> list;
  static constexpr auto fields() {
    using F = RecordField<Sample>;
    return std::array{F{"x", &Sample::x},         F{"flag", &Sample::flag},
                      F{"count", &Sample::count}, F{"size", &Sample::size},
                      F{"name", &Sample::name},   F{"list", &Sample::list}};
  }
};

Sample sample() {
  Sample s;
  s.x = -0.1;
  s.flag = true;
  s.count = -7;
  s.size = 9007199254740992u;  // 2^53, the largest count a double holds exactly
  s.name = "ab\xff";
  s.list = {std::numeric_limits<double>::infinity(), std::nan(""), -0.0, 1e-310};
  return s;
}

TEST(RunRecord, ValuesFollowTheFieldTable) {
  // By hand: each scalar once, a text or a list as its length and then its entries.
  const RecordValues expected = {-0.1,         1.0,
                                 -7.0,         9007199254740992.0,
                                 3.0,          97.0,
                                 98.0,         static_cast<double>(static_cast<char>('\xff')),
                                 4.0,          std::numeric_limits<double>::infinity(),
                                 std::nan(""), -0.0,
                                 1e-310};
  const RecordValues got = record_values(sample());
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_TRUE(std::bit_cast<std::uint64_t>(got[i]) == std::bit_cast<std::uint64_t>(expected[i]) ||
                (std::isnan(got[i]) && std::isnan(expected[i])))
        << "number " << i << ": " << got[i] << " vs " << expected[i];
}

TEST(RunRecord, ReadBackBitForBit) {
  const Sample a = sample();
  Sample b;
  ASSERT_EQ(record_from_values(record_values(a), b), "");
  EXPECT_EQ(std::bit_cast<std::uint64_t>(b.x), std::bit_cast<std::uint64_t>(a.x));
  EXPECT_EQ(b.flag, a.flag);
  EXPECT_EQ(b.count, a.count);
  EXPECT_EQ(b.size, a.size);
  EXPECT_EQ(b.name, a.name);
  ASSERT_EQ(b.list.size(), a.list.size());
  EXPECT_TRUE(std::isinf(b.list[0]) && std::isnan(b.list[1]) && std::signbit(b.list[2]));
  EXPECT_EQ(b.list[3], 1e-310);
}

TEST(RunRecord, NumbersThatAreNotTheRecordAreRefusedWithTheReason) {
  const RecordValues good = record_values(sample());
  auto refused = [](RecordValues v) {
    Sample s;
    return record_from_values(v, s);
  };
  RecordValues shorter(good.begin(), good.begin() + 3);
  EXPECT_EQ(refused(shorter), "expected field 'size' at number 4, got the end");
  RecordValues longer = good;
  longer.push_back(1.0);
  EXPECT_EQ(refused(longer), "expected 13 numbers (the record's fields), got 14");
  RecordValues fraction = good;
  fraction[2] = 2.5;
  EXPECT_EQ(refused(fraction), "expected a whole number for field 'count' at number 3, got 2.5");
  RecordValues negative_size = good;
  negative_size[3] = -1.0;
  EXPECT_EQ(refused(negative_size), "expected a whole number for field 'size' at number 4, got -1");
  RecordValues long_name = good;
  long_name[4] = 100.0;  // more characters than numbers are left
  EXPECT_EQ(refused(long_name),
            "expected a length in [0, 8] for field 'name' at number 5, got 100");
  RecordValues nan_length = good;
  nan_length[8] = std::nan("");
  EXPECT_EQ(refused(nan_length),
            "expected a length in [0, 4] for field 'list' at number 9, got nan");
  EXPECT_EQ(refused({}), "expected field 'x' at number 1, got the end");
}

TEST(RunRecord, JsonNamesEveryField) {
  const nlohmann::json j = record_json(sample());
  EXPECT_EQ(j.size(), Sample::fields().size());
  EXPECT_EQ(j.at("x"), -0.1);
  EXPECT_EQ(j.at("flag"), true);
  EXPECT_EQ(j.at("count"), -7);
  EXPECT_EQ(j.at("size"), 9007199254740992u);
  EXPECT_EQ(j.at("list").size(), 4u);
  // NaN and inf are not JSON numbers: null in the text.
  EXPECT_EQ(j.at("list").dump(), "[null,null,-0.0,1e-310]");
}

TEST(RunRecord, ColumnIsTheFieldOfEveryRecord) {
  std::vector<Sample> runs(3);
  for (int i = 0; i < 3; ++i) runs[static_cast<std::size_t>(i)].count = 10 * i - 5;
  EXPECT_EQ(column(runs, &Sample::count), (std::vector<double>{-5.0, 5.0, 15.0}));
}

// Every experiment's record: unique names, and the values of a record read back to themselves.
template <NamedRecord R>
void expect_well_formed(const char* what) {
  std::set<std::string> names;
  for (const auto& f : R::fields())
    EXPECT_TRUE(names.insert(std::string(f.name)).second) << what << ": " << f.name;
  R r;
  const RecordValues v = record_values(r);
  R back;
  EXPECT_EQ(record_from_values(v, back), "") << what;
  EXPECT_EQ(record_values(back), v) << what;
  EXPECT_EQ(record_json(r).size(), R::fields().size()) << what;
}

TEST(RunRecord, ExperimentRecordsAreWellFormed) {
  expect_well_formed<implicit::experiments::MclRunRecord>("mcl");
  expect_well_formed<implicit::experiments::MclGlobalRunRecord>("mcl global");
  expect_well_formed<implicit::experiments::SlamRunRecord>("slam");
  expect_well_formed<implicit::experiments::HimmelblauRunRecord>("himmelblau");
  expect_well_formed<implicit::experiments::ProposalGainRunRecord>("proposal gain");
  expect_well_formed<implicit::experiments::SlitTableRow>("slit");
}

}  // namespace
