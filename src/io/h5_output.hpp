// HDF5 output of one run (schema in docs/hdf5-schema.md), written atomically with the C API.
#pragma once
#include <string>

#include "sim/result.hpp"

namespace truss::io {

// Throws InputError if `path` cannot be an output file: it exists and force is false
// ("error: output file exists: PATH (use --force to overwrite)"), it is a directory, or its
// directory does not exist. Lets a program refuse before it spends time simulating.
void check_output_path(const std::string& path, bool force);

// Writes the run to `path` (schema_version 1, kind "single_run"), storing resolved_scene_toml as
// the root attribute scene_toml. The file is written under a temporary name in the same directory
// (.NAME.tmp.PID) and renamed onto `path` only when complete, so `path` is never left
// half-written. Without force an existing `path` is never replaced: check_output_path() runs
// first, and the final rename refuses to replace a file that appeared in the meantime.
// Throws InputError (see check_output_path) or std::runtime_error on an HDF5 or file-system
// error (the temporary file is removed).
void write_run_h5(const std::string& path, const sim::RunResult& result,
                  const std::string& resolved_scene_toml, bool force);

}  // namespace truss::io
