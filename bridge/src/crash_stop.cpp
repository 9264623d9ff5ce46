#include "bridge/crash_stop.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace tsmh::bridge {
namespace {

// The installed CrashStop: a signal handler gets no context argument, so
// this static is the only way it can reach its prepared outputs.
std::atomic<CrashStop*> g_installed{nullptr};

std::string canonical(const std::string& path) {
  char resolved[PATH_MAX];
  return realpath(path.c_str(), resolved) != nullptr ? std::string(resolved) : path;
}

}  // namespace

CrashStop::CrashStop() {
  null_fd_ = open("/dev/null", O_WRONLY | O_CLOEXEC);
  if (null_fd_ < 0)
    throw std::runtime_error(std::string("crash stop: cannot open /dev/null: ") +
                             std::strerror(errno));
  for (auto& m : muted_)
    m.store(-1, std::memory_order_relaxed);
}

CrashStop::~CrashStop() {
  uninstall();
  for (std::size_t i = 0; i < used_; ++i)
    close(outputs_[i].fd);
  close(null_fd_);
}

std::size_t CrashStop::add_datagram(const UdpmEndpoint& endpoint) {
  if (used_ == kMaxOutputs) throw std::runtime_error("crash stop: too many outputs");
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error(std::string("crash stop: socket: ") + std::strerror(errno));
  // As LCM's own send socket (lcm_udpm.c): the URL's TTL, loopback on, so
  // subscribers on this host hear it; never connect()ed (LCM: Linux then
  // has problems multicasting to localhost).
  const int ttl = endpoint.ttl;
  const int loop = 1;
  if (setsockopt(fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl) != 0 ||
      setsockopt(fd, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop) != 0) {
    const int err = errno;
    close(fd);
    throw std::runtime_error(std::string("crash stop: setsockopt: ") + std::strerror(err));
  }
  Output& o = outputs_[used_];
  o.fd = fd;
  o.datagram = true;
  o.to = endpoint.group;
  return used_++;
}

std::size_t CrashStop::add_node(const std::string& node) {
  if (used_ == kMaxOutputs) throw std::runtime_error("crash stop: too many outputs");
  const int fd = node.empty() ? dup(null_fd_) : open(node.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0)
    throw std::runtime_error("crash stop: cannot open " + (node.empty() ? "/dev/null" : node) +
                             ": " + std::strerror(errno));
  Output& o = outputs_[used_];
  o.fd = fd;
  o.datagram = false;
  return used_++;
}

bool CrashStop::reopen_node(std::size_t output, const std::string& node) noexcept {
  if (output >= used_ || outputs_[output].datagram) return false;
  const int fd = open(node.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) return false;
  // dup2 replaces the old file under the same number atomically.
  const bool ok = dup2(fd, outputs_[output].fd) >= 0;
  close(fd);
  return ok;
}

bool CrashStop::adopt_descriptor(std::size_t output, int fd) noexcept {
  if (output >= used_ || outputs_[output].datagram) return false;
  // dup3: dup2 would drop close-on-exec from the handler's descriptor.
  return dup3(fd >= 0 ? fd : null_fd_, outputs_[output].fd, O_CLOEXEC) >= 0;
}

bool CrashStop::set(std::size_t output, const std::uint8_t* bytes, std::size_t size) noexcept {
  if (output >= used_ || size > kMaxBytes || size == 0) return false;
  // Once the handler has started, the buffer it reads must stay as it is.
  if (crashing_.load()) return false;
  Output& o = outputs_[output];
  const int now = o.current.load();
  const int spare = now == 0 ? 1 : 0;
  std::memcpy(o.bytes[static_cast<std::size_t>(spare)].data(), bytes, size);
  o.size[static_cast<std::size_t>(spare)] = size;
  o.current.store(spare);
  return true;
}

void CrashStop::clear(std::size_t output) noexcept {
  if (output < used_) outputs_[output].current.store(-1);
}

std::size_t CrashStop::armed_outputs() const noexcept {
  std::size_t n = 0;
  for (std::size_t i = 0; i < used_; ++i)
    n += outputs_[i].current.load() >= 0 ? 1 : 0;
  return n;
}

std::size_t CrashStop::find_senders(std::initializer_list<int> keep_ports,
                                    std::initializer_list<std::string> nodes) {
  std::vector<std::string> node_paths;
  for (const auto& n : nodes)
    if (!n.empty()) node_paths.push_back(canonical(n));
  std::vector<int> found;
  DIR* dir = opendir("/proc/self/fd");
  if (dir != nullptr) {
    while (const dirent* entry = readdir(dir)) {
      const int fd = std::atoi(entry->d_name);
      if (fd <= 2 || fd == dirfd(dir) || fd == null_fd_) continue;
      bool own = false;
      for (std::size_t i = 0; i < used_; ++i)
        own = own || outputs_[i].fd == fd;
      if (own) continue;
      int type = 0;
      socklen_t type_len = sizeof type;
      if (getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &type_len) == 0) {
        sockaddr_in address{};
        socklen_t address_len = sizeof address;
        if (type != SOCK_DGRAM ||
            getsockname(fd, reinterpret_cast<sockaddr*>(&address), &address_len) != 0 ||
            address.sin_family != AF_INET)
          continue;
        bool keep = false;
        for (int port : keep_ports)
          keep = keep || (port > 0 && ntohs(address.sin_port) == port);
        if (!keep) found.push_back(fd);
        continue;
      }
      if (node_paths.empty()) continue;
      char target[PATH_MAX];
      const std::string link = "/proc/self/fd/" + std::string(entry->d_name);
      const ssize_t n = readlink(link.c_str(), target, sizeof target - 1);
      if (n <= 0) continue;
      target[n] = '\0';
      for (const auto& p : node_paths)
        if (p == target) found.push_back(fd);
    }
    closedir(dir);
  }
  for (std::size_t i = 0; i < kMaxMuted; ++i)
    muted_[i].store(i < found.size() ? found[i] : -1);
  return found.size();
}

void CrashStop::install() {
  CrashStop* expected = nullptr;
  if (!g_installed.compare_exchange_strong(expected, this))
    throw std::logic_error("crash stop: another one is installed");
  struct sigaction sa {};
  sa.sa_handler = &CrashStop::on_signal;
  // The others stay blocked while one is handled in this thread;
  // SA_RESETHAND: a fault inside the handler, or a second thread's fault,
  // ends the process with the default action instead of re-entering it.
  sigemptyset(&sa.sa_mask);
  for (int s : kSignals)
    sigaddset(&sa.sa_mask, s);
  sa.sa_flags = SA_RESETHAND;
  for (int s : kSignals)
    sigaction(s, &sa, nullptr);
  installed_ = true;
}

void CrashStop::uninstall() noexcept {
  if (!installed_) return;
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  for (int s : kSignals)
    sigaction(s, &dfl, nullptr);
  g_installed.store(nullptr);
  installed_ = false;
}

void CrashStop::on_signal(int sig) noexcept {
  const int saved_errno = errno;
  if (CrashStop* self = g_installed.load()) self->fire();
  errno = saved_errno;
  // The default action is back (SA_RESETHAND) and `sig` is blocked until we
  // return: raised now, it is delivered on return and ends the process as
  // it would have without us. A real fault would also recur on return.
  raise(sig);
}

void CrashStop::fire() noexcept {
  crashing_.store(true);
  // 1. Nothing else leaves this process after our messages.
  for (auto& m : muted_) {
    const int fd = m.load();
    if (fd >= 0) dup2(null_fd_, fd);
  }
  timeval pause{0, 1000};  // a send already inside the kernel completes first
  select(0, nullptr, nullptr, nullptr, &pause);
  // 2. The prepared outputs, as they are.
  for (std::size_t i = 0; i < used_; ++i) {
    const Output& o = outputs_[i];
    const int b = o.current.load();
    if (b < 0) continue;
    const auto& bytes = o.bytes[static_cast<std::size_t>(b)];
    const std::size_t size = o.size[static_cast<std::size_t>(b)];
    if (o.datagram)
      sendto(o.fd, bytes.data(), size, MSG_DONTWAIT | MSG_NOSIGNAL,
             reinterpret_cast<const sockaddr*>(&o.to), sizeof o.to);
    else
      (void)!write(o.fd, bytes.data(), size);
  }
}

}  // namespace tsmh::bridge
