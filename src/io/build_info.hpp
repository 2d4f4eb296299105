// build_info.hpp — the build's identity, printed by --version and written into every output file
// (docs/hdf5-schema.md: software_version, git_revision). Defined in a source generated at build
// time (cmake/build_info.cmake): a build after a commit or a pull records the revision it was
// built from, and only that source recompiles when the revision changes.
#pragma once
#include <string_view>

namespace truss::io {

std::string_view get_software_version();  // the project's version (CMake's PROJECT_VERSION)
// The short git hash of the sources, with "-dirty" when a tracked file differed from it at build
// time; "unknown" outside a git checkout.
std::string_view get_git_revision();

}  // namespace truss::io
