// robotdyn/kernels/rolling_contact.hpp: a wheel rolling without slipping on a terrain, twin of
// robotdyn/constraints/rolling_contact.py (RollingWheel: standard, omni and support wheels; its fast path
// robotdyn/constraints/wheel_group.py on a plane). The formulas (rolling_contact.py's docstring; the concepts page
// docs/concepts.md, "Rolling contact"; notes: rolling-contact-and-projection.md):
//
//   geometry   a = R_f axis (world axle), u = (n - (n.a) a) / |n - (n.a) a| from contact point to centre,
//              p = c - R u with n taken at p itself (a fixed point on curved terrain), contact frame
//              t1 = a x n / |a x n| (rolling direction), t2 = n x t1, n (RollingWheel._geometry)
//   rows       A_w v = v_c + omega x (p - c) - u Rdot (the material point at p), rows D E^T A_w with
//              E = [t1 t2 n] and D the wheel's (nd, 3) directions (standard: I; omni: rollers' axis and n)
//   residual   phi = (p_z - f(p_x, p_y)) / |(-f_x, -f_y, 1)| on the normal row (holonomic)
//   drift      D (Edot^T s + E^T Adot_w v), s = A_w v,
//              Adot_w v = a_c^0 + omegadot^0 x r + omega x rdot - udot Rdot, r = p - c, rdot = -(R udot + Rdot u),
//              udot from a 3x3 implicit solve on curved terrain (RollingWheel.drift, WheelGroup._drift)
#pragma once

#include "common.hpp"
#include "terrain.hpp"

namespace robotdyn {
namespace kernels {

struct Wheel {
  int frame;       // index into the Evaluator's frames
  Vector3d axis;   // axle in the wheel frame (unit)
  double radius;   // m (plus q[radius_index] when radius_index >= 0)
  int radius_index;
  Eigen::Matrix<double, Eigen::Dynamic, 3, 0, 3, 3> D;  // (nd, 3) rows as coefficients of (t1, t2, n)
};

struct WheelGeometry {  // configuration-level quantities of one wheel
  Vector3d a, u, n, t1, t2;
  Matrix3d N;  // dn/dp on a curved terrain
  double na, nw, nc1, R;
  Vector3d p;  // contact point (world)
  double phi;  // signed distance above the terrain [m] (a compliant wheel's penetration is -phi)
  int row;     // the wheel's first row
};

// Contact point and frame of wheel `wh` (RollingWheel._geometry), its rows D E^T A_w into A from `row` on, and its
// residuals; oMf its frame's placement, J its LOCAL_WORLD_ALIGNED Jacobian (6, nv); leaves the geometry in g and
// A_w (3, nv) in Aw. Returns the next row.
inline int wheel_rows(const Wheel& wh, const Terrain& terrain, const pin::SE3& oMf, const Matrix6x& J,
                      const VectorXd& q, int row, WheelGeometry& g, MatrixXd& Aw, MatrixXd& A, VectorXd& residual) {
  g.row = row;
  g.R = wh.radius;
  if (wh.radius_index >= 0) {
    g.R += q[wh.radius_index];
    if (g.R <= 0) throw Fallback("radius not positive");
  }
  g.a.noalias() = oMf.rotation() * wh.axis;
  const Vector3d c = oMf.translation();
  const bool flat = terrain.flat();
  Vector3d n = terrain.normal(c[0], c[1]), p;
  int it = 0;
  for (; it < 100; ++it) {
    g.na = n.dot(g.a);
    Vector3d wv = n - g.na * g.a;
    g.nw = wv.norm();
    if (g.nw < 1e-9) throw Fallback("wheel lying flat");
    g.u = wv / g.nw;
    p = c - g.R * g.u;
    if (flat) break;
    const Vector3d m = terrain.normal(p[0], p[1]);
    const double d2 = (m - n).squaredNorm();
    n = m;
    if (d2 < 1e-30) {
      g.na = n.dot(g.a);
      wv = n - g.na * g.a;
      g.nw = wv.norm();
      g.u = wv / g.nw;
      p = c - g.R * g.u;
      break;
    }
  }
  if (it == 100) throw Fallback("contact point did not converge");
  g.n = n;
  g.p = p;
  double f;
  Eigen::Vector2d grad;
  Eigen::Matrix2d H;
  terrain.eval(p[0], p[1], f, grad, H);
  const double norm = std::sqrt(1.0 + grad.squaredNorm());
  const double phi = (p[2] - f) / norm;
  g.phi = phi;
  if (!flat) {  // Terrain.normal_derivative
    Matrix3d dm = Matrix3d::Zero();
    dm.block<2, 2>(0, 0) = -H;
    g.N = (Matrix3d::Identity() - n * n.transpose()) * dm / norm;
  }
  const Vector3d c1 = g.a.cross(n);
  g.nc1 = c1.norm();
  g.t1 = c1 / g.nc1;
  g.t2 = n.cross(g.t1);
  const Vector3d r = -g.R * g.u;
  Aw = J.topRows<3>();
  Aw.noalias() -= skew(r).lazyProduct(J.bottomRows<3>());
  if (wh.radius_index >= 0) Aw.col(wh.radius_index) -= g.u;
  Matrix3d ET;
  ET.row(0) = g.t1.transpose();
  ET.row(1) = g.t2.transpose();
  ET.row(2) = n.transpose();
  const int nd = static_cast<int>(wh.D.rows());
  const Eigen::Matrix<double, Eigen::Dynamic, 3, 0, 3, 3> W = wh.D * ET;
  A.middleRows(row, nd).noalias() = W.lazyProduct(Aw);
  for (int r2 = 0; r2 < nd; ++r2) residual[row + r2] = wh.D(r2, 2) != 0.0 ? phi : 0.0;
  return row + nd;
}

// Drift D (Edot^T s + E^T acc) of wheel `wh` (RollingWheel.drift, WheelGroup._drift) into drift from `row` on, after
// wheel_rows (g, Aw) and an RNEA pass at (q, v, 0) that left data's joint velocities and accelerations; fid is its
// Pinocchio frame (Aw, v read only). Returns the next row.
inline int wheel_drift(const Wheel& wh, const WheelGeometry& g, const Terrain& terrain, const pin::Model& model,
                       const pin::Data& data, int fid, MatrixXd& Aw, VectorXd& v, int row, VectorXd& drift) {
  const pin::Motion vf = pin::getFrameVelocity(model, data, fid, pin::LOCAL_WORLD_ALIGNED);
  const pin::Motion af = classical_acceleration(model, data, fid, vf);
  const Vector3d omega = vf.angular(), cdot = vf.linear();
  const double Rdot = wh.radius_index >= 0 ? v[wh.radius_index] : 0.0;
  const Vector3d& n = g.n;
  const Vector3d adot = omega.cross(g.a);
  const Vector3d rhs_const = -(n.dot(adot)) * g.a - g.na * adot;
  Vector3d udot, ndot = Vector3d::Zero();
  if (terrain.flat()) {
    udot = (rhs_const - g.u * g.u.dot(rhs_const)) / g.nw;
  } else {
    const Matrix3d P = (Matrix3d::Identity() - g.u * g.u.transpose()) / g.nw;
    const Matrix3d QaN = (Matrix3d::Identity() - g.a * g.a.transpose()) * g.N;
    const Matrix3d K = Matrix3d::Identity() + g.R * (P * QaN);
    const Vector3d rhs = P * (QaN * (cdot - Rdot * g.u) + rhs_const);
    udot = K.partialPivLu().solve(rhs);
    ndot = g.N * (cdot - g.R * udot - Rdot * g.u);
  }
  const Vector3d r = -g.R * g.u, rdot = -g.R * udot - Rdot * g.u;
  const Vector3d c1dot = adot.cross(n) + g.a.cross(ndot);
  const Vector3d t1dot = (c1dot - g.t1 * g.t1.dot(c1dot)) / g.nc1;
  const Vector3d t2dot = ndot.cross(g.t1) + n.cross(t1dot);
  Vector3d acc = af.linear() + af.angular().cross(r) + omega.cross(rdot);
  if (wh.radius_index >= 0) acc -= udot * Rdot;
  const Vector3d s = Aw * v;
  const Vector3d d(t1dot.dot(s) + g.t1.dot(acc), t2dot.dot(s) + g.t2.dot(acc), ndot.dot(s) + n.dot(acc));
  const int nd = static_cast<int>(wh.D.rows());
  drift.segment(row, nd).noalias() = wh.D * d;
  return row + nd;
}

// The wheel's contact force along (t1, t2, n) from its rows' multipliers: D^T lambda (robotdyn/contact/
// contact_forces.py: the force the ground exerts on the wheel at the contact point [N]).
inline Vector3d wheel_force(const Wheel& wh, const WheelGeometry& g, const VectorXd& lambda) {
  return wh.D.transpose() * lambda.segment(g.row, wh.D.rows());
}

}  // namespace kernels
}  // namespace robotdyn
