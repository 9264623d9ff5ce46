#include "bridge/stop_signals.hpp"

#include <pthread.h>

#include <cstdio>
#include <cstring>

namespace tsmh::bridge {

sigset_t terminating_signals() noexcept {
  sigset_t set;
  sigemptyset(&set);
  static constexpr int kSignals[] = {SIGHUP,   SIGINT,  SIGQUIT,   SIGUSR1, SIGUSR2,
                                     SIGALRM,  SIGTERM, SIGVTALRM, SIGPROF, SIGXCPU,
                                     SIGXFSZ,  SIGIO,   SIGPWR,
#ifdef SIGSTKFLT
                                     SIGSTKFLT
#endif
  };
  for (int s : kSignals)
    sigaddset(&set, s);
  for (int s = SIGRTMIN; s <= SIGRTMAX; ++s)
    sigaddset(&set, s);
  return set;
}

sigset_t block_terminating_signals() noexcept {
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGPIPE, &ignore, nullptr);
  const sigset_t set = terminating_signals();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  return set;
}

const char* signal_name(int sig) noexcept {
  if (sig >= SIGRTMIN && sig <= SIGRTMAX) {
    static thread_local char buf[24];
    std::snprintf(buf, sizeof buf, "SIGRTMIN+%d", sig - SIGRTMIN);
    return buf;
  }
  const char* abbrev = sigabbrev_np(sig);
  if (!abbrev) return "unknown signal";
  static thread_local char buf[24];
  std::snprintf(buf, sizeof buf, "SIG%s", abbrev);
  return buf;
}

bool terminating_signal_pending(const sigset_t& set) noexcept {
  sigset_t pending;
  sigemptyset(&pending);
  if (sigpending(&pending) != 0) return false;
  for (int s = 1; s < NSIG; ++s)
    if (sigismember(&set, s) == 1 && sigismember(&pending, s) == 1) return true;
  return false;
}

}  // namespace tsmh::bridge
