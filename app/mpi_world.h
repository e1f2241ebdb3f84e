// The MPI world of `tb check` under mpirun (docs/checks-and-reports.md, "Under mpirun"): when the
// program was started by an MPI launcher and the build found MPI, rank r of n runs the checks
// whose index in the selection is r mod n and rank 0 gathers every record, writes them, the
// results and the report. Otherwise (no launcher, or a build without MPI) one rank of one.
#pragma once

#include <string>
#include <vector>

namespace tb::mpi {

struct World {
  int rank = 0, size = 1;
};

// Initialises MPI only when an MPI launcher started the program (its environment names a world
// size); idempotent. finalize() ends it (no-op when it was not started).
World init(int* argc, char*** argv);
const World& world();
void finalize();
// Whether this build can run under mpirun at all.
bool available();

// Rank 0 receives every rank's string in rank order; the other ranks get an empty vector.
std::vector<std::string> gather(const std::string& mine);
// Rank 0's value on every rank.
int broadcast(int value);

}  // namespace tb::mpi
