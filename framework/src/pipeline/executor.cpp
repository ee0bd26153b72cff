#include "rkhs/pipeline/executor.hpp"

#include <algorithm>
#include <thread>

namespace rkhs::pipeline {

int LocalExecutor::default_threads() const {
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

std::optional<StoredRun> LocalExecutor::run(const StudyDefinition& study,
                                            const std::vector<TrialSpec>& trials,
                                            RunOptions options, ResultStore* store, bool fresh) {
  return run_with_store(study, trials, options, store, fresh);
}

}  // namespace rkhs::pipeline
