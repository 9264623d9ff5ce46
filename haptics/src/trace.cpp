#include "haptics/trace.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <stdexcept>

#include "estimator/atomic_file.hpp"
#include "files/file_size_limit.hpp"

namespace tsmh::haptics {

void encode_trace_row(const TraceRow& r, int joints, double* out) noexcept {
  *out++ = r.t;
  *out++ = static_cast<double>(r.state_seq);
  *out++ = r.state;
  *out++ = r.flags;
  *out++ = r.lateness_us;
  for (int j = 0; j < joints; ++j) {
    const auto& q = r.joints[static_cast<std::size_t>(j)];
    for (double v : {q.master_q, q.slave_ref, q.tau_in, q.tau_out_est, q.torque_cmd, q.x_in,
                     q.x_out, q.true_tau_out, q.true_x_out, q.indentation, q.contact_force})
      *out++ = v;
  }
}

Trace::Trace(int joints, std::size_t capacity)
    : joints_(joints),
      width_(trace_row_width(joints)),
      storage_(capacity * trace_row_width(joints)),
      data_(storage_.data()),
      capacity_(capacity) {}

Trace::Trace(int joints, const double* data, std::size_t rows, std::shared_ptr<const void> owner,
             std::uint64_t dropped)
    : joints_(joints),
      width_(trace_row_width(joints)),
      data_(data),
      capacity_(rows),
      size_(rows),
      dropped_(dropped),
      owner_(std::move(owner)) {}

void Trace::append(const TraceRow& row) noexcept {
  if (size_ < capacity_ && !owner_) {
    encode_trace_row(row, joints_, storage_.data() + size_ * width_);
    ++size_;
  } else {
    ++dropped_;
  }
}

TraceRow Trace::operator[](std::size_t i) const noexcept {
  const double* p = data_ + i * width_;
  TraceRow r;
  r.t = *p++;
  r.state_seq = static_cast<std::int64_t>(*p++);
  r.state = static_cast<std::int32_t>(*p++);
  r.flags = static_cast<std::int32_t>(*p++);
  r.lateness_us = *p++;
  for (int j = 0; j < joints_; ++j) {
    auto& q = r.joints[static_cast<std::size_t>(j)];
    for (double* v : {&q.master_q, &q.slave_ref, &q.tau_in, &q.tau_out_est, &q.torque_cmd, &q.x_in,
                      &q.x_out, &q.true_tau_out, &q.true_x_out, &q.indentation, &q.contact_force})
      *v = *p++;
  }
  return r;
}

void Trace::write_csv(const std::string& path) const {
  estimator::write_file_atomically(path, [&](std::ostream& out) {
    out << "t,state_seq,state,flags,lateness_us";
    for (int j = 0; j < joints_; ++j) {
      for (const char* c : {"q", "ref", "tau_in", "tau_est", "cmd", "x_in", "x_out", "true_tau_out",
                            "true_x_out", "indentation", "contact_force"})
        out << ',' << c << '_' << j;
    }
    out << '\n';
    char buf[32];
    const auto put = [&](double v) {
      const auto r = std::to_chars(buf, buf + sizeof buf, v);
      out << ',';
      out.write(buf, r.ptr - buf);
    };
    for (std::size_t i = 0; i < size_; ++i) {
      const double* p = data_ + i * width_;
      const auto t = std::to_chars(buf, buf + sizeof buf, p[0]);
      out.write(buf, t.ptr - buf);
      out << ',' << static_cast<std::int64_t>(p[1]) << ',' << static_cast<std::int32_t>(p[2]) << ','
          << static_cast<std::int32_t>(p[3]);
      for (std::size_t k = 4; k < width_; ++k)
        put(p[k]);
      out << '\n';
    }
  });
}

TraceSpool::TraceSpool(int joints, const std::filesystem::path& dir, std::uint64_t max_rows)
    : joints_(joints),
      max_rows_(max_rows),
      ring_(std::make_unique<bridge::SpscQueue<TraceRow, kRingRows>>()) {
  const std::string folder = dir.empty() ? std::string(".") : dir.string();
  fd_ = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd_ < 0) {  // a file system without O_TMPFILE: create, then unlink at once
    std::string name = folder + "/.haptic-server-trace-XXXXXX";
    fd_ = mkstemp(name.data());
    if (fd_ >= 0) ::unlink(name.c_str());
  }
  if (fd_ < 0)
    throw std::runtime_error("cannot create the trace's spool file in '" + folder +
                             "': " + std::strerror(errno));
  file_ = fdopen(::dup(fd_), "wb");
  if (file_ == nullptr) {
    ::close(fd_);
    throw std::runtime_error(std::string("trace spool: fdopen failed: ") + std::strerror(errno));
  }
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  writer_ = std::thread([this] { run(); });
}

TraceSpool::~TraceSpool() {
  stop_.store(true, std::memory_order_release);
  if (writer_.joinable()) writer_.join();
  if (file_) std::fclose(file_);
  if (fd_ >= 0) ::close(fd_);
}

void TraceSpool::append(const TraceRow& row) noexcept {
  if (pushed_ >= max_rows_ || !ring_->push(row)) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  ++pushed_;
}

void TraceSpool::run() noexcept {
  std::vector<double> buf(trace_row_width(joints_));
  TraceRow row;
  for (;;) {
    const bool stopping = stop_.load(std::memory_order_acquire);
    bool any = false;
    while (ring_->pop(row)) {
      any = true;
      encode_trace_row(row, joints_, buf.data());
      if (std::fwrite(buf.data(), sizeof(double), buf.size(), file_) != buf.size()) {
        if (!failed_.exchange(true, std::memory_order_relaxed))
          failed_errno_.store(errno, std::memory_order_relaxed);
      } else
        written_.fetch_add(1, std::memory_order_relaxed);
    }
    if (stopping) break;
    if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (std::fflush(file_) != 0 && !failed_.exchange(true, std::memory_order_relaxed))
    failed_errno_.store(errno, std::memory_order_relaxed);
}

Trace TraceSpool::finish() {
  stop_.store(true, std::memory_order_release);
  if (writer_.joinable()) writer_.join();
  if (failed_.load()) {
    struct stat st {};
    const std::uint64_t size = ::fstat(fd_, &st) == 0 ? static_cast<std::uint64_t>(st.st_size) : 0;
    if (files::hit_file_size_limit(failed_errno_.load(), size))
      throw std::runtime_error(files::file_size_limit_message("the trace's spool file") +
                               ": no trace or report written");
    throw std::runtime_error(std::string("writing the trace's spool file failed (") +
                             std::strerror(failed_errno_.load()) + ")");
  }
  const std::uint64_t rows = written_.load();
  const std::size_t bytes = rows * trace_row_width(joints_) * sizeof(double);
  if (rows == 0) return Trace(joints_, nullptr, 0, nullptr, dropped());
  void* map = ::mmap(nullptr, bytes, PROT_READ, MAP_PRIVATE, fd_, 0);
  if (map == MAP_FAILED)
    throw std::runtime_error(std::string("cannot map the trace's spool file: ") +
                             std::strerror(errno));
  std::shared_ptr<const void> owner(
      map, [bytes](const void* p) { ::munmap(const_cast<void*>(p), bytes); });
  return Trace(joints_, static_cast<const double*>(map), rows, std::move(owner), dropped());
}

}  // namespace tsmh::haptics
