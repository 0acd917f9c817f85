// The build's provenance: the project's version and the git commit the binary was built from
// ("-dirty" when tracked files differed from it; "unknown" outside a git checkout). Written at
// build time by scripts/build_info.cmake.
#pragma once

namespace rtu {

const char* rtunit_version();
const char* rtunit_commit();

}  // namespace rtu
