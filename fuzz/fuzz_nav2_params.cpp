// Fuzz target: the ROS 2 parameter file reader (src/robot/nav2_params.cpp), as
// `implicit mcl --params` runs it. It must return AMCL's block or throw ParseError; another
// exception, a crash, a hang or a sanitizer report is a finding.

#include <cstdint>
#include <string>

#include "implicit/core/error.hpp"
#include "implicit/robot/nav2_params.hpp"
#include "scratch.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto p = implicit::robot::parse_nav2_parameters(implicit::fuzz::as_text(data, size),
                                                          "fuzz.yaml", "amcl");
    // Each key is there once, so looking it up finds that entry.
    for (const auto& e : p.entries)
      if (p.find(e.key) != &e) __builtin_trap();
  } catch (const implicit::ParseError&) {
  }
  return 0;
}
