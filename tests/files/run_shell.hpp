#pragma once
// Running a program the way a user does, through bash (so that `ulimit -f`
// and redirections apply), with a time limit and the child's peak memory:
// a read that blocks or grows without bound shows up as a timeout or a
// large peak instead of a hung test.

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

namespace tsmh::files::test {

struct ShellRun {
  int code = -1;   ///< exit code; -1 when killed by a signal or timed out
  int signal = 0;  ///< the signal that ended it
  bool timed_out = false;
  double seconds = 0;   ///< wall time
  long max_rss_kb = 0;  ///< peak resident memory of the program
  std::string output;   ///< stdout + stderr
};

/// `bash -c SCRIPT` in its own process group; killed (SIGKILL to the group)
/// after `timeout_s`. The script should `exec` the program so that the peak
/// memory is the program's.
inline ShellRun run_shell(const std::string& script, const std::filesystem::path& log,
                          double timeout_s = 30.0) {
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    setpgid(0, 0);
    FILE* f = std::fopen(log.c_str(), "w");
    if (f == nullptr) _exit(126);
    dup2(fileno(f), 1);
    dup2(fileno(f), 2);
    // The test's own blocked or ignored signals must not leak into the program.
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    signal(SIGXFSZ, SIG_DFL);
    execl("/bin/bash", "bash", "-c", script.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  ShellRun r;
  int status = 0;
  rusage ru{};
  for (;;) {
    const pid_t done = wait4(pid, &status, WNOHANG, &ru);
    if (done == pid) break;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (elapsed > timeout_s && !r.timed_out) {
      r.timed_out = true;
      kill(-pid, SIGKILL);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.max_rss_kb = ru.ru_maxrss;
  if (WIFEXITED(status) && !r.timed_out) r.code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  r.output = ss.str();
  return r;
}

/// 'text' quoted for bash.
inline std::string q(const std::string& text) {
  std::string out = "'";
  for (const char c : text) {
    if (c == '\'')
      out += "'\\''";
    else
      out += c;
  }
  return out + "'";
}

}  // namespace tsmh::files::test
