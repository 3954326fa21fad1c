// robotdyn/kernels/compliant_contact.hpp: wheels that fly and land, twin of robotdyn/contact/compliant_contact.py
// (NormalLaw, CompliantWheel.state) with the friction laws of robotdyn/contact/friction.py (RegularisedCoulomb,
// LinearTyre): the normal force law of penetration and the tangential friction law of a compliant wheel, in their
// order of operations.
//
// With the wheel's rows A (3, nv): t1^T A_w, t2^T A_w (A_w the world Jacobian of the wheel's material point at the
// contact point, t1, t2 its contact frame's tangents) and G = d phi / dq (penetration_gradient below), and its signed
// distance phi above the terrain:
//   penetration delta = -phi [m], its rate deltadot = -(A v)_n = -dphi/dt [m/s], slip s = (A v)_(t1, t2) [m/s];
//   normal force f_n = N(delta, deltadot) >= 0 (zero for delta <= 0: the wheel flies; never pulling):
//     linear         f_n = max(0, k delta + c deltadot)
//     Hunt-Crossley  f_n = max(0, delta^n (k + lambda deltadot))   (Hunt & Crossley 1975; Marhefka & Orin 1999)
//   tangential force on the law's directions D (rows, coefficients of (t1, t2)), while f_n > 0:
//     F_t = -f_n D^T D c(D^T D s), c the friction law's coefficient (F_t = -f_n c(s), robotdyn/contact/friction.py)
//   generalised force Q = A^T (F_t1, F_t2, f_n); friction power F_t . s (<= 0); damper power
//   -(f_n - f_e(delta)) deltadot (<= 0), f_e the law's elastic part; stored energy U(delta) = int_0^delta f_e.
//
// penetration_gradient (compliant_contact.penetration_gradient): G = n^T A_w + w^T J_p, w = (-phi s^2 H grad f, 0)
// (s = 1 / |(-f_x, -f_y, 1)|, H the terrain's Hessian, both at p: the gradient of phi(x) = (x_z - f) s at p is
// n + (phi / s)(grad s, 0)), J_p = J_c - u dR/dq - R J_u the contact point's Jacobian, J_u = K^-1 P (Q_a N (J_c -
// u dR/dq) + (a n^T + (n.a) I)[a]_x J_omega) (P = (I - u u^T) / nw, Q_a = I - a a^T, N = dn/dp, K = I + R P Q_a N:
// the implicit solve of rolling_contact.hpp's drift); on a plane (H = 0) G = n^T A_w.
#pragma once

#include "rolling_contact.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace robotdyn {
namespace kernels {

// A normal force law (NormalLaw): kind 0 linear (k [N/m], c [N s/m]), 1 Hunt-Crossley (k [N/m^n], c = lambda
// [N s/m^(n+1)], exponent n >= 1).
struct NormalLaw {
  int kind = 0;
  double k = 0.0, c = 0.0, n = 1.0;
  double force(double delta, double rate) const {
    if (!(delta > 0.0)) return 0.0;
    if (kind == 0) return std::max(0.0, k * delta + c * rate);
    return std::max(0.0, std::pow(delta, n) * (k + c * rate));
  }
  double elastic(double delta) const {
    if (!(delta > 0.0)) return 0.0;
    return kind == 0 ? k * delta : k * std::pow(delta, n);
  }
  double potential(double delta) const {
    if (!(delta > 0.0)) return 0.0;
    return kind == 0 ? 0.5 * k * delta * delta : k * std::pow(delta, n + 1.0) / (n + 1.0);
  }
};

// A friction law's coefficient c(s) (FrictionLaw.coefficient): code -1 none (frictionless), 0 RegularisedCoulomb
// c = p0 s / sqrt(|s|^2 + p1^2) (p0 = mu, p1 = slip velocity [m/s]), 1 LinearTyre c = p0 s if p0 |s| <= p1, else
// p1 s / |s| (p0 = stiffness [s/m], p1 = mu).
struct FrictionLaw {
  int code = -1;
  double p0 = 0.0, p1 = 0.0;
  Eigen::Vector2d coefficient(const Eigen::Vector2d& s) const {
    if (code == 0) return p0 * s / std::sqrt(s.dot(s) + p1 * p1);
    const double speed = std::sqrt(s.dot(s));
    if (speed * p0 <= p1) return p0 * s;
    return p1 * s / speed;
  }
};

// A compliant wheel: the wheel whose contact geometry it uses, its laws and the law's tangential directions.
struct CompliantContact {
  int wheel;  // the index of its contact geometry (the evaluator's wheel list)
  NormalLaw normal;
  FrictionLaw friction;
  Eigen::Matrix<double, Eigen::Dynamic, 2, 0, 2, 2> D;  // (0..2, 2): rows, coefficients of (t1, t2)
};

// One compliant wheel's contact at a state (CompliantWheel.state).
struct ContactState {
  double delta = 0.0, rate = 0.0;               // penetration [m], its rate [m/s]
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // (F_t1, F_t2, f_n) [N]
  double friction_power = 0.0, damper_power = 0.0;  // [W], both <= 0
};

// The contact of `c` with rolling rows A (3, nv) and signed distance phi [m] at full velocities v; adds A^T force to Q.
inline ContactState add_compliant_contact(const CompliantContact& c, double phi,
                                          const Eigen::Ref<const Eigen::Matrix<double, 3, Eigen::Dynamic>>& A,
                                          const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> Q) {
  ContactState out;
  const Eigen::Vector3d u = A * v;
  out.delta = -phi;
  out.rate = -u[2];
  const double fn = c.normal.force(out.delta, out.rate);
  const Eigen::Vector2d slip = u.head<2>();
  Eigen::Vector2d ft = Eigen::Vector2d::Zero();
  if (fn > 0.0 && c.friction.code >= 0 && c.D.rows() > 0) {
    const Eigen::Vector2d along = c.D.transpose() * (c.D * slip);  // the slip along the law's directions
    ft = -fn * (c.D.transpose() * (c.D * c.friction.coefficient(along)));
  }
  out.force << ft[0], ft[1], fn;
  out.damper_power = out.delta > 0.0 ? -(fn - c.normal.elastic(out.delta)) * out.rate : 0.0;
  out.friction_power = ft.dot(slip);
  Q.noalias() += A.transpose() * out.force;
  return out;
}

// G = d phi / dq (1, nv) of wheel `wh` with geometry g (wheel_rows at the configured q), its frame's
// LOCAL_WORLD_ALIGNED Jacobian J (6, nv) and A_w (3, nv), into row (see the top of this file).
inline void penetration_gradient(const Wheel& wh, const WheelGeometry& g, const Terrain& terrain, const Matrix6x& J,
                                 const MatrixXd& Aw, Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> row) {
  row.noalias() = g.n.transpose() * Aw;
  if (terrain.flat()) return;
  double f;
  Eigen::Vector2d grad;
  Eigen::Matrix2d H;
  terrain.eval(g.p[0], g.p[1], f, grad, H);
  Vector3d w = Vector3d::Zero();
  w.head<2>() = -g.phi / (1.0 + grad.squaredNorm()) * (H * grad);
  if (w.isZero(0.0)) return;
  const Matrix3d P = (Matrix3d::Identity() - g.u * g.u.transpose()) / g.nw;
  const Matrix3d Qa = Matrix3d::Identity() - g.a * g.a.transpose();
  const Matrix3d K = Matrix3d::Identity() + g.R * (P * Qa * g.N);
  const Vector3d z = P * K.transpose().partialPivLu().solve(w);  // w^T K^-1 P = z^T
  // w^T J_c - (w.u) dR/dq - R z^T (Q_a N (J_c - u dR/dq) + (a n^T + (n.a) I)[a]_x J_omega)
  const Eigen::RowVector3d zn = z.transpose() * (Qa * g.N);
  const Eigen::RowVector3d cw = w.transpose() - g.R * zn;
  row.noalias() += cw * J.topRows<3>();
  const Matrix3d L = (g.a * g.n.transpose() + g.na * Matrix3d::Identity()) * skew(g.a);
  row.noalias() -= (g.R * (z.transpose() * L)) * J.bottomRows<3>();
  if (wh.radius_index >= 0) row[wh.radius_index] -= cw.dot(g.u);
}

}  // namespace kernels
}  // namespace robotdyn
