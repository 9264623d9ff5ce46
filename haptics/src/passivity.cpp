#include "haptics/passivity.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tsmh::haptics {

void validate(const PassivityConfig& c) {
  if (!(c.max_damping_nms_per_rad > 0.0) || !(c.max_damping_nms_per_rad <= 100.0))
    throw std::invalid_argument("passivity.max_damping_nms_per_rad: must be within (0, 100]");
  if (!(c.max_brake_nm >= 0.0) || !(c.max_brake_nm <= 1000.0))
    throw std::invalid_argument("passivity.max_brake_nm: must be within [0, 1000]");
}

PassivityChannel::PassivityChannel(const PassivityConfig& c) : c_(c) {
  validate(c_);
}

void PassivityChannel::reset() noexcept {
  master_ = {};
  slave_ = {};
  have_q_ = have_x_ = false;
  dq_ = 0.0;
  dissipated_ = damping_ = absorbed_ = 0.0;
  active_ = false;
}

void PassivityChannel::slave_sample(double torque, double angle) noexcept {
  if (!std::isfinite(torque) || !std::isfinite(angle)) return;
  // The torque reported with the previous sample acted over the motion to
  // this one (it is what the master rendered meanwhile).
  if (have_x_) slave_.add(f_prev_ * (angle - x_prev_));
  x_prev_ = angle;
  f_prev_ = torque;
  have_x_ = true;
}

double PassivityChannel::control(double q, double request, double dt_s) noexcept {
  active_ = false;
  damping_ = 0.0;
  if (!std::isfinite(q)) {
    dq_ = 0.0;
    return request;
  }
  dq_ = have_q_ ? q - q_prev_ : 0.0;
  q_prev_ = q;
  have_q_ = true;
  if (!c_.enabled || !std::isfinite(request) || !(dt_s > 0.0)) return request;
  // Energy the master port would put into the network this tick; when < 0
  // the network hands it to the operator and W_M falls by as much.
  const double into = -request * dq_;
  const double would_be = observed_energy() + std::min(into, 0.0);
  if (would_be >= 0.0 || dq_ == 0.0) return request;
  // Solve F dq = W (the energy available; < 0 after safety's rate limit
  // trailed an earlier cut): the torque that leaves W_M exactly at 0, as a
  // damper alpha = (request - F) / v, bounded. With W < 0 that is a brake
  // against the motion, and what the brake absorbs is credited to W_M
  // (commit), as the dissipation of Artigas et al.'s controller is: the
  // deficit is paid back and the brake lets go, instead of holding on
  // (measured before the credit: +0.3 N m against every release at 10 ms).
  const double v = dq_ / dt_s;
  const double wanted = observed_energy() / dq_;
  const double alpha = std::min((request - wanted) / v, c_.max_damping_nms_per_rad);
  if (!(alpha > 0.0)) return request;
  double corrected = request - alpha * v;
  // A brake (the correction reversed the torque) is capped: repaying a
  // deficit slowly is safe, a kick against the operator is not.
  if (corrected * request < 0.0 && std::fabs(corrected) > c_.max_brake_nm)
    corrected = std::copysign(c_.max_brake_nm, corrected);
  const double alpha_used = (request - corrected) / v;
  damping_ = alpha_used;
  active_ = true;
  dissipated_ += (request - corrected) * dq_;
  return corrected;
}

void PassivityChannel::commit(double rendered) noexcept {
  if (!std::isfinite(rendered)) return;
  const double into = -rendered * dq_;
  if (active_ && into > 0.0)
    absorbed_ += into;  // the controller's brake, not energy into the channel
  else
    master_.add(into);
}

}  // namespace tsmh::haptics
