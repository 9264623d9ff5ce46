#pragma once
// A child process of an end-to-end test or benchmark (haptic-server,
// virtual-slave, external-master-adapter): stdout and stderr into a file,
// core dumps off (a test that ends it with SIGSEGV must not fill the disk),
// the default signal dispositions and mask of a shell; killed (SIGKILL) if
// still running when the test is done with it.

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bridge/stop_signals.hpp"

namespace tsmh::haptics::test {

/// A child process with stdout+stderr in a file; killed (SIGKILL) if still
/// running when destroyed.
class Child {
 public:
  /// `cpu` >= 0: the whole process runs on that CPU only. `env`: variables
  /// set in the child (an empty value unsets one).
  Child(const std::vector<std::string>& argv, const std::filesystem::path& log, int cpu = -1,
        const std::map<std::string, std::string>& env = {})
      : log_(log) {
    pid_ = fork();
    if (pid_ == 0) {
      for (const auto& [k, v] : env) {
        if (v.empty())
          unsetenv(k.c_str());
        else
          setenv(k.c_str(), v.c_str(), 1);
      }
      if (cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(cpu, &set);
        sched_setaffinity(0, sizeof set, &set);
      }
      const rlimit no_core{0, 0};
      setrlimit(RLIMIT_CORE, &no_core);
      // The test blocks nothing, but be explicit: the child starts with the
      // default dispositions, as from a shell.
      sigset_t none;
      sigemptyset(&none);
      pthread_sigmask(SIG_SETMASK, &none, nullptr);
      const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, 1);
      dup2(fd, 2);
      std::vector<char*> args;
      for (const auto& a : argv)
        args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
  }
  Child(const std::vector<std::string>& argv, const std::filesystem::path& log,
        const std::map<std::string, std::string>& env)
      : Child(argv, log, -1, env) {}
  ~Child() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  void signal(int sig) const { kill(pid_, sig); }
  bool running() {
    if (exited_) return false;
    int st = 0;
    if (waitpid(pid_, &st, WNOHANG) == pid_) {
      exited_ = true;
      status_ = st;
    }
    return !exited_;
  }
  /// Waits up to `timeout` for the exit; returns the exit code, or -1 (still
  /// running or killed by a signal: then `what` says which).
  int wait(std::chrono::milliseconds timeout, std::string* what = nullptr) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (running() && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (!exited_) {
      if (what) *what = "still running";
      return -1;
    }
    if (WIFSIGNALED(status_)) {
      if (what) *what = std::string("killed by ") + bridge::signal_name(WTERMSIG(status_));
      return -1;
    }
    return WEXITSTATUS(status_);
  }
  /// Waits up to `timeout`; true when the process has ended (status() then
  /// says how: exit code or signal).
  bool wait_for_end(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (running() && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    return exited_;
  }
  /// The waitpid() status, once the process has ended.
  int status() const { return status_; }
  std::string log() const {
    std::ifstream in(log_);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
  int status_ = 0;
  std::filesystem::path log_;
};

}  // namespace tsmh::haptics::test
