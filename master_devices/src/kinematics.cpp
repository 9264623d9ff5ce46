#include "master_devices/kinematics.hpp"

#include <cmath>

namespace tsmh::master_devices {

namespace {

// The handle P is where two circles of radius L around the elbows A and B
// meet. Differentiating |P - A|^2 = L^2 and |P - B|^2 = L^2 gives
//   (P - A) . dP = (P - A) . dA,   (P - B) . dP = (P - B) . dB
// with dA = l (-sin t1, cos t1) dt1, dB = l (-sin t2, cos t2) dt2: a 2x2
// system M dP = diag(a1, a2) dt, so J = M^-1 diag(a1, a2).
bool pantograph(const PantographGeometry& g, double t1, double t2, JointArray& x, Jacobian& J) {
  const double ax = g.l_m * std::cos(t1), ay = g.l_m * std::sin(t1);
  const double bx = g.d_m + g.l_m * std::cos(t2), by = g.l_m * std::sin(t2);
  const double ex = bx - ax, ey = by - ay;  // elbow A -> elbow B
  const double e2 = ex * ex + ey * ey;
  const double e = std::sqrt(e2);
  if (!(e > 1e-9) || e >= 2.0 * g.L_m) return false;
  const double h = std::sqrt(g.L_m * g.L_m - e2 / 4.0);  // midpoint -> handle
  // The handle on the left of A -> B (the +y side for elbows side by side).
  const double px = ax + ex / 2.0 - h * ey / e;
  const double py = ay + ey / 2.0 + h * ex / e;
  const double m11 = px - ax, m12 = py - ay, m21 = px - bx, m22 = py - by;
  const double det = m11 * m22 - m12 * m21;
  if (std::abs(det) < 1e-12) return false;  // distal links aligned: no unique force
  const double a1 = m11 * (-g.l_m * std::sin(t1)) + m12 * (g.l_m * std::cos(t1));
  const double a2 = m21 * (-g.l_m * std::sin(t2)) + m22 * (g.l_m * std::cos(t2));
  J = {};
  J[0][0] = m22 * a1 / det;
  J[0][1] = -m12 * a2 / det;
  J[1][0] = -m21 * a1 / det;
  J[1][1] = m11 * a2 / det;
  x = {};
  x[0] = px;
  x[1] = py;
  return true;
}

}  // namespace

bool forward_kinematics(const KinematicsSpec& k, const JointArray& q, JointArray& x, Jacobian& J) {
  for (std::size_t j = 0; j < k.joints; ++j)
    if (!std::isfinite(q[j])) return false;
  if (k.type == KinematicsType::kPantograph) return pantograph(k.pantograph, q[0], q[1], x, J);
  x = {};
  J = {};
  for (std::size_t j = 0; j < k.joints; ++j) {
    x[j] = q[j];
    J[j][j] = 1.0;
  }
  return true;
}

std::string_view to_string(KinematicsType t) {
  return t == KinematicsType::kPantograph ? "pantograph" : "identity";
}

}  // namespace tsmh::master_devices
