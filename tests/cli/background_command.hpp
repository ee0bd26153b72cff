#pragma once
// Starting the rkhs-study executable of this build as a background process, for tests that
// signal, wait for or race with a running command (the store and store-proof CLI tests).

#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

namespace rkhs::test {

/// Starts `rkhs-study args` in its own process with stdout and stderr in `log` (SIGINT not
/// ignored: the child inherits this process's dispositions); returns its pid.
inline pid_t start_rkhs_study(const std::vector<std::string>& args,
                              const std::filesystem::path& log = "/dev/null") {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv{const_cast<char*>(RKHS_STUDY_EXECUTABLE)};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(out, 1);
    dup2(out, 2);
    execv(RKHS_STUDY_EXECUTABLE, argv.data());
    _exit(127);
  }
  return pid;
}

}  // namespace rkhs::test
