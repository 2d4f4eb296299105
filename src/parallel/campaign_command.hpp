// truss-campaign: the whole campaign job on every rank (mpi_driver/ only initialises MPI).
//
//   mpirun -np N truss-campaign CAMPAIGN.toml -o RESULTS.h5 [--set key=value]... [--resume] [--force]
//
// Every rank parses the command line; rank 0 parses the campaign and sends its resolved text to
// the others; any error is reported once (rank 0) and every rank exits with status 2 before a
// single run starts. Rank 0 checks the output and the journal (restoring an interrupted session
// with --resume); then the engine (engine.hpp) evaluates the method's rounds, and rank 0 writes
// the end of the HDF5 file.
//
// Exit status: 0 the results file is written (failed runs are data in it); 2 bad input (command
// line, campaign file, an existing output or journal), nothing written; 3 an I/O or internal error;
// 4 the results file is written, but most runs are invalid input (parallel/progress.hpp).
#pragma once
#include <mpi.h>

#include <functional>
#include <memory>

#include "methods/method_table.hpp"

namespace truss::parallel {

inline constexpr int kExitOk = 0;
inline constexpr int kExitBadInput = 2;
inline constexpr int kExitIoError = 3;
inline constexpr int kExitMostlyInvalid = 4;  // the file is written, but most runs are invalid input
inline constexpr int kExitNoResult = 5;       // the file is written, but the method has no result (its reason printed)
inline constexpr int kExitNotAssessed = 6;    // the file is written, but its verdict is NOT ASSESSED (why printed)

// Collective over comm; returns the exit status (the same on every rank). `methods`: the rows
// ensemble.method names, by which every rank parses the campaign and makes its method (a test
// passes the built-in rows and one of its own).
int run_campaign_command(int argc, char** argv, MPI_Comm comm,
                         const methods::MethodTable& methods = methods::builtin_methods());

}  // namespace truss::parallel
