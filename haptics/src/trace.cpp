#include "haptics/trace.hpp"

#include <charconv>

#include "estimator/atomic_file.hpp"

namespace tsmh::haptics {

Trace::Trace(int joints, std::size_t capacity) : joints_(joints), rows_(capacity) {}

void Trace::append(const TraceRow& row) noexcept {
  if (size_ < rows_.size()) {
    rows_[size_++] = row;
  } else {
    ++dropped_;
  }
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
      const auto& r = rows_[i];
      const auto t = std::to_chars(buf, buf + sizeof buf, r.t);
      out.write(buf, t.ptr - buf);
      out << ',' << r.state_seq << ',' << r.state << ',' << r.flags;
      put(r.lateness_us);
      for (int j = 0; j < joints_; ++j) {
        const auto& q = r.joints[static_cast<std::size_t>(j)];
        for (double v : {q.master_q, q.slave_ref, q.tau_in, q.tau_out_est, q.torque_cmd, q.x_in,
                         q.x_out, q.true_tau_out, q.true_x_out, q.indentation, q.contact_force})
          put(v);
      }
      out << '\n';
    }
  });
}

}  // namespace tsmh::haptics
