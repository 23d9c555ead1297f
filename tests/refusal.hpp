#pragma once
// The shape of a refusal test: the call throws InvalidArgument, and its message contains the
// words that name what was wrong (and where).
#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "implicit/core/error.hpp"

namespace implicit::test_support {

inline void expect_refused(const std::function<void()>& f, const std::string& words) {
  try {
    f();
    ADD_FAILURE() << "expected InvalidArgument mentioning '" << words << "'";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

}  // namespace implicit::test_support
