#pragma once
// Running helper programs (the peer, lcm-logger, lcm-logplayer, tsm) from
// tests: fork + exec with captured stdout, optional new network namespace.

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
#include <vector>

namespace tsmh::bridge::test {

struct RunResult {
  int exit_code = -1;  ///< -1: did not exit normally
  std::string output;  ///< stdout + stderr
};

/// Exit code a child uses when it could not enter a new network namespace.
inline constexpr int kNoNamespace = 77;

/// Runs argv to completion. With `new_netns` the child first unshares its
/// network namespace (needs root; exit code kNoNamespace when refused).
inline RunResult run(const std::vector<std::string>& argv, bool new_netns = false) {
  int fds[2];
  if (pipe(fds) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], 1);
    dup2(fds[1], 2);
    close(fds[0]);
    close(fds[1]);
    if (new_netns && unshare(CLONE_NEWNET) != 0) _exit(kNoNamespace);
    std::vector<char*> args;
    for (const auto& a : argv)
      args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execvp(args[0], args.data());
    _exit(127);
  }
  close(fds[1]);
  RunResult r;
  char buf[4096];
  ssize_t n;
  while ((n = read(fds[0], buf, sizeof buf)) > 0)
    r.output.append(buf, static_cast<std::size_t>(n));
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  return r;
}

/// A background process (e.g. lcm-logger), stopped with SIGINT on stop() or
/// destruction. Output goes to /dev/null.
class Background {
 public:
  explicit Background(const std::vector<std::string>& argv) {
    pid_ = fork();
    if (pid_ == 0) {
      const int devnull = open("/dev/null", O_WRONLY);
      dup2(devnull, 1);
      dup2(devnull, 2);
      std::vector<char*> args;
      for (const auto& a : argv)
        args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execvp(args[0], args.data());
      _exit(127);
    }
  }
  ~Background() { stop(); }
  Background(const Background&) = delete;
  Background& operator=(const Background&) = delete;

  bool started() const { return pid_ > 0; }
  /// SIGINT and wait; returns the exit status as waitpid reports it.
  int stop() {
    if (pid_ <= 0) return -1;
    kill(pid_, SIGINT);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return status;
  }

 private:
  pid_t pid_ = -1;
};

}  // namespace tsmh::bridge::test
