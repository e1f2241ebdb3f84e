#include "app/mpi_world.h"

#include <cstdlib>
#include <stdexcept>

#ifdef TB_HAVE_MPI
#include <mpi.h>
#endif

namespace tb::mpi {
namespace {
World g_world;
bool g_started = false;

#ifdef TB_HAVE_MPI
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"})
    if (std::getenv(v) != nullptr) return true;
  return false;
}
#endif
}  // namespace

bool available() {
#ifdef TB_HAVE_MPI
  return true;
#else
  return false;
#endif
}

World init(int* argc, char*** argv) {
#ifdef TB_HAVE_MPI
  if (!g_started && launched_by_mpi()) {
    MPI_Init(argc, argv);
    g_started = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &g_world.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &g_world.size);
  }
#else
  (void)argc;
  (void)argv;
#endif
  return g_world;
}

const World& world() { return g_world; }

void finalize() {
#ifdef TB_HAVE_MPI
  if (g_started) MPI_Finalize();
#endif
  g_started = false;
}

std::vector<std::string> gather(const std::string& mine) {
  if (g_world.size == 1) return {mine};
#ifdef TB_HAVE_MPI
  const int n = static_cast<int>(mine.size());
  std::vector<int> sizes(static_cast<size_t>(g_world.size), 0);
  MPI_Gather(&n, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::vector<int> offsets(sizes.size(), 0);
  int total = 0;
  for (size_t r = 0; r < sizes.size(); ++r) {
    offsets[r] = total;
    total += sizes[r];
  }
  std::string all(g_world.rank == 0 ? static_cast<size_t>(total) : 0, '\0');
  MPI_Gatherv(mine.data(), n, MPI_CHAR, all.data(), sizes.data(), offsets.data(), MPI_CHAR, 0, MPI_COMM_WORLD);
  if (g_world.rank != 0) return {};
  std::vector<std::string> out;
  for (size_t r = 0; r < sizes.size(); ++r) out.push_back(all.substr(static_cast<size_t>(offsets[r]), static_cast<size_t>(sizes[r])));
  return out;
#else
  throw std::logic_error("mpi::gather: more than one rank in a build without MPI");
#endif
}

int broadcast(int value) {
#ifdef TB_HAVE_MPI
  if (g_world.size > 1) MPI_Bcast(&value, 1, MPI_INT, 0, MPI_COMM_WORLD);
#endif
  return value;
}

}  // namespace tb::mpi
