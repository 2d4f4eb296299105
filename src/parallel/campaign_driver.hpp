// truss-campaign: the whole campaign job on every rank (mpi_driver/ only initialises MPI).
//
//   mpirun -np N truss-campaign CAMPAIGN.toml -o RESULTS.h5 [--set key=value]... [--resume] [--force]
//
// Every rank parses the campaign and the command line; any error is reported once (rank 0) and
// every rank exits with status 2 before a single run starts. Rank 0 checks the output and the
// journal, schedules the runs (parallel/scheduler.hpp), journals every result, and writes the
// HDF5 file at the end.
//
// Exit status: 0 the results file is written (failed runs are data in it); 2 bad input (command
// line, campaign file, an existing output or journal), nothing written; 3 an I/O or internal error;
// 4 the results file is written, but most runs are invalid input (campaign/progress.hpp).
#pragma once
#include <mpi.h>

namespace truss::parallel {

inline constexpr int kExitOk = 0;
inline constexpr int kExitBadInput = 2;
inline constexpr int kExitIoError = 3;
inline constexpr int kExitMostlyInvalid = 4;  // the file is written, but most runs are invalid input

// Collective over comm; returns the exit status (the same on every rank).
int run_campaign_command(int argc, char** argv, MPI_Comm comm);

}  // namespace truss::parallel
