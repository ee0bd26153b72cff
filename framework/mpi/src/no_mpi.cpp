// rkhs/mpi/distributed.hpp in a build without MPI: nothing can be distributed.

#include "rkhs/mpi/distributed.hpp"

namespace rkhs::distributed {

bool available() noexcept {
  return false;
}
int usable_cpus() noexcept {
  return 1;
}

Session::Session(int&, char**&) {
  throw std::runtime_error(
      "this rkhs-study was built without MPI (RKHS_STUDY_MPI=OFF, or no MPI found when it was "
      "configured), so --mpi is not available; install Open MPI (libopenmpi-dev) and rebuild, or "
      "split the study with --shard K/N and combine the stores with `rkhs-study merge`");
}

Session::~Session() = default;

int Session::default_threads() const noexcept {
  return 1;
}
std::vector<std::string> Session::gather(const std::string& text) const {
  return {text};
}
std::string Session::broadcast(const std::string& value) const {
  return value;
}
void Session::abort(const std::string& why, int) const {
  throw std::runtime_error(why);
}

JobStatistics distribute(const Session&, const Job&) {
  throw std::runtime_error("this rkhs-study was built without MPI");
}

}  // namespace rkhs::distributed
