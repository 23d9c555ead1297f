#pragma once
// Library version and the commit it was built from.
namespace implicit {
const char* version();
const char* git_commit();
}  // namespace implicit
