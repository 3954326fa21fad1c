// robotdyn/kernels/rolling_contact_derivatives.hpp: configuration derivatives of a rolling wheel's rows, twin of
// robotdyn/constraints/row_derivatives.py (wheel_geometry_dq, wheel_velocity_dq, terrain_normal_dp, wheel_drift_dq)
// beside the wheel's values in rolling_contact.hpp (robotdyn/constraints/rolling_contact.py): d(A x)/dq at fixed x,
// the drift's dgamma/dq at fixed v and the rows' time derivative Adot (RollingWheel.rows), flat and curved terrain,
// constant or joint-driven radius, the same formulas in the same order.
#pragma once

#include <cmath>
#include <vector>

#include "frame_derivatives.hpp"

namespace robotdyn {
namespace derivs {

// dq of a wheel's contact geometry (wheel_geometry_dq): 3 x n each, eR the radius coordinate's unit row
struct WheelGeometryDq {
  Matrix3x a, u, n, t1, t2, r;
  RowX eR;
  const Matrix3x& E(int i) const { return i == 0 ? t1 : i == 1 ? t2 : n; }
};

// The terrain's third derivatives f_ijk (Terrain.third of RampTerrain, SineTerrain, BumpTerrain) for the
// evaluator's terrain codes (0 plane, 1 sine a sin(kx x + ky y + phase), 2 smooth step(s)); F3[i][j][k].
template <class T>
void terrain_third(const T& terrain, double x, double y, double F3[2][2][2]) {
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) F3[i][j][k] = 0.0;
  const double* c = terrain.c;
  if (terrain.kind == 1) {
    const double kv[2] = {c[1], c[2]};
    const double s = -c[0] * std::cos(c[1] * x + c[2] * y + c[3]);
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j)
        for (int k = 0; k < 2; ++k) F3[i][j][k] = s * kv[i] * kv[j] * kv[k];
  } else if (terrain.kind == 2) {
    auto step3 = [&](double x0) {  // BumpTerrain._step3
      const double t = std::tanh((x - x0) / c[2]);
      return -c[0] * (1.0 - t * t) * (1.0 - 3.0 * t * t) / (c[2] * c[2] * c[2]);
    };
    F3[0][0][0] = step3(c[1]) - (std::isnan(c[3]) ? 0.0 : step3(c[1] + c[3]));
  }
}

// dN/dp_x, dN/dp_y of the terrain normal's derivative N = (I - n n^T) D / |m| (terrain_normal_dp)
template <class T>
void terrain_normal_dp(const T& terrain, const Vector3d& p, Matrix3d out[2]) {
  double f;
  Eigen::Vector2d g;
  Eigen::Matrix2d H;
  terrain.eval(p[0], p[1], f, g, H);
  double F3[2][2][2];
  terrain_third(terrain, p[0], p[1], F3);
  const Vector3d m(-g[0], -g[1], 1.0);
  const double norm = m.norm();
  const Vector3d n = m / norm;
  Matrix3d D = Matrix3d::Zero();
  D.block<2, 2>(0, 0) = -H;
  const Matrix3d Pn = Matrix3d::Identity() - n * n.transpose();
  const Matrix3d N = Pn * D / norm;
  for (int al = 0; al < 2; ++al) {
    Matrix3d dD = Matrix3d::Zero();
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) dD(i, j) = -F3[i][j][al];
    const Vector3d Na = N.col(al);
    out[al] = (-(Na * n.transpose() + n * Na.transpose()) * D + Pn * dD) / norm - N * (n.dot(D.col(al))) / norm;
  }
}

// g: the evaluator's geometry of the wheel (a, u, n, t1, t2, N, na, nw, nc1, R, p); jac: its frame's world
// Jacobian (6 x n); radius_index: the radius coordinate or -1
template <class G>
void wheel_geometry_dq(const G& g, const Matrix6x& jac, int radius_index, bool flat, WheelGeometryDq& out) {
  const int nv = static_cast<int>(jac.cols());
  out.eR.setZero(nv);
  if (radius_index >= 0) out.eR[radius_index] = 1.0;
  const Matrix3x Jc = jac.topRows<3>(), Jw = jac.bottomRows<3>();
  out.a = -skew3(g.a) * Jw;
  const Matrix3d P = (Matrix3d::Identity() - g.u * g.u.transpose()) / g.nw;
  const Matrix3x rhs = -g.a * (g.n.transpose() * out.a) - g.n.dot(g.a) * out.a;
  if (flat) {
    out.u = P * rhs;
    out.n.setZero(3, nv);
  } else {
    const Matrix3d Qa = Matrix3d::Identity() - g.a * g.a.transpose();
    const Matrix3d K = Matrix3d::Identity() + g.R * P * Qa * g.N;
    const Matrix3x Jcu = Jc - g.u * out.eR;
    out.u = K.partialPivLu().solve(P * (Qa * g.N * Jcu + rhs));
    out.n = g.N * (Jc - g.R * out.u - g.u * out.eR);
  }
  const Matrix3x C1 = -skew3(g.n) * out.a + skew3(g.a) * out.n;
  out.t1 = (C1 - g.t1 * (g.t1.transpose() * C1)) / g.nc1;
  out.t2 = -skew3(g.t1) * out.n + skew3(g.n) * out.t1;
  out.r = -g.R * out.u - g.u * out.eR;
}

// d(A x)/dq of the wheel's rows at fixed x (wheel_velocity_dq): D (rows x 3), V/dV the frame's world velocity at
// x and its q-derivative, xR the radius coordinate's rate in x; written into out (rows x n)
template <class G, class Out>
void wheel_velocity_dq(const G& g, const WheelGeometryDq& gd, const Eigen::Ref<const MatrixXd>& D, const Vector6d& V,
                       const Matrix6x& dV, double xR, Out&& out) {
  const Vector3d r = -g.R * g.u;
  const Vector3d w = V.tail<3>();
  const Vector3d s = V.head<3>() + w.cross(r) - g.u * xR;
  const Matrix3x ds = dV.topRows<3>() + cross_d(w, dV.bottomRows<3>(), r, gd.r) - xR * gd.u;
  const Vector3d E[3] = {g.t1, g.t2, g.n};
  Matrix3x dEs(3, ds.cols());
  for (int i = 0; i < 3; ++i) dEs.row(i) = E[i].transpose() * ds + s.transpose() * gd.E(i);
  out.noalias() = D.lazyProduct(dEs);  // (coefficient-wise: 3-deep products, no matrix-product kernel set-up)
}

// dgamma/dq at fixed v of the wheel's drift rows (wheel_drift_dq) into drift_out (rows x n), and the rows' time
// derivative Adot = Wdot Aw + W Awdot (RollingWheel.rows) into adot_out (rows x n).
// V/dV, Acc/dAcc: the frame's world velocity and classical acceleration at v with q-derivatives; dJ: its world
// Jacobian's time variation along v; Aw: the wheel's world contact-point Jacobian (3 x n) at q. The matrices may hold
// a subset of the n columns (all of those that can be nonzero: ReducedDerivatives' compact columns): radius_index
// indexes v, radius_col the radius coordinate's column among them (-1: none).
template <class G, class T, class Out1, class Out2>
void wheel_drift_dq(const G& g, const WheelGeometryDq& gd, const Eigen::Ref<const MatrixXd>& D, const T& terrain,
                    bool flat, const Matrix6x& jac, int radius_index, int radius_col, const VectorXd& v,
                    const Vector6d& V,
                    const Matrix6x& dV, const Vector6d& Acc, const Matrix6x& dAcc, const Matrix6x& dJ,
                    const MatrixXd& Aw, Out1&& drift_out, Out2&& adot_out) {
  const int nv = static_cast<int>(jac.cols());
  const Vector3d& a = g.a;
  const Vector3d& n = g.n;
  const Vector3d& u = g.u;
  const double R = g.R, nw = g.nw, nc1 = g.nc1;
  const Vector3d w = V.tail<3>();
  const Matrix3x dw = dV.bottomRows<3>();
  const double Rd = radius_index >= 0 ? v[radius_index] : 0.0;
  const RowX& eR = gd.eR;
  const Vector3d r = -R * u;
  const Matrix3x &dr = gd.r, &du = gd.u, &da = gd.a, &dn = gd.n;
  Matrix3d N = Matrix3d::Zero();
  Matrix3d dNdp[2] = {Matrix3d::Zero(), Matrix3d::Zero()};
  Matrix3x dp;
  if (!flat) {
    N = g.N;
    terrain_normal_dp(terrain, g.p, dNdp);
    dp = jac.topRows<3>() - u * eR - R * du;  // p = c - R u
  }
  auto dN_times = [&](const Vector3d& y) -> Matrix3x {  // d(N y)/dq at fixed y
    if (flat) return Matrix3x::Zero(3, nv);
    return (dNdp[0] * y) * dp.row(0) + (dNdp[1] * y) * dp.row(1);
  };
  const Matrix3d P = (Matrix3d::Identity() - u * u.transpose()) / nw;
  const Matrix3d Qa = Matrix3d::Identity() - a * a.transpose();
  const double na = n.dot(a);
  const RowX dna = a.transpose() * dn + n.transpose() * da;
  const RowX dnw = -na * dna / nw;
  auto dP_times = [&](const Vector3d& y) -> Matrix3x {  // d(P y)/dq at fixed y, P = (I - u u^T)/nw
    return (-(u * (y.transpose() * du)) - du * u.dot(y)) / nw - (P * y) * dnw / nw;
  };
  auto dQ_times = [&](const Vector3d& y) -> Matrix3x {  // d(Qa y)/dq at fixed y, Qa = I - a a^T
    return -(da * a.dot(y) + a * (y.transpose() * da));
  };
  // rates at (q, v)
  const Vector3d cd = V.head<3>();
  const Matrix3x dcd = dV.topRows<3>();
  const Vector3d adot = w.cross(a);
  const Matrix3x dadot = cross_d(w, dw, a, da);
  const double nad = n.dot(adot);
  const Vector3d rc = -nad * a - na * adot;
  const Matrix3x drc = -a * (adot.transpose() * dn + n.transpose() * dadot) - nad * da - adot * dna - na * dadot;
  Vector3d udot, ndot;
  Matrix3x dudot, dndot;
  if (flat) {
    // N = 0: m1 = N e = 0, m2 = rc, K = I, udot = z, dudot = dz, ndot = 0: the sums below with their zero terms
    // left out (the same numbers)
    udot = P * rc;
    dudot = dP_times(rc) + P * drc;
    ndot.setZero();
    dndot.setZero(3, nv);
  } else {
    const Vector3d e = cd - Rd * u;
    const Matrix3x de = dcd - Rd * du;
    const Vector3d m1 = N * e;
    const Matrix3x dm1 = dN_times(e) + N * de;
    const Vector3d m2 = Qa * m1 + rc;
    const Matrix3x dm2 = dQ_times(m1) + Qa * dm1 + drc;
    const Vector3d z = P * m2;
    const Matrix3x dz = dP_times(m2) + P * dm2;
    const Matrix3d K = Matrix3d::Identity() + R * P * Qa * N;
    const auto Klu = K.partialPivLu();
    udot = Klu.solve(z);
    const Vector3d x1 = N * udot, x2 = Qa * x1;
    const Matrix3x dK_udot = (P * x2) * eR + R * (dP_times(x2) + P * (dQ_times(x1) + Qa * dN_times(udot)));
    dudot = Klu.solve(dz - dK_udot);
    const Vector3d hh = cd - R * udot - Rd * u;
    const Matrix3x dhh = dcd - udot * eR - R * dudot - Rd * du;
    ndot = N * hh;
    dndot = dN_times(hh) + N * dhh;
  }
  const Vector3d rdot = -R * udot - Rd * u;
  const Matrix3x drdot = -udot * eR - R * dudot - Rd * du;
  const Vector3d& t1 = g.t1;
  const Matrix3x& dt1 = gd.t1;
  const Vector3d c1d = adot.cross(n) + a.cross(ndot);
  const Matrix3x dc1d = cross_d(adot, dadot, n, dn) + cross_d(a, da, ndot, dndot);
  const RowX dnc1 = t1.transpose() * cross_d(a, da, n, dn);
  const Vector3d y = c1d - t1 * t1.dot(c1d);
  const Matrix3x dy = dc1d - dt1 * t1.dot(c1d) - t1 * (c1d.transpose() * dt1 + t1.transpose() * dc1d);
  const Vector3d t1d = y / nc1;
  const Matrix3x dt1d = dy / nc1 - y * dnc1 / (nc1 * nc1);
  const Vector3d t2d = ndot.cross(t1) + n.cross(t1d);
  const Matrix3x dt2d = cross_d(ndot, dndot, t1, dt1) + cross_d(n, dn, t1d, dt1d);
  // s and acc
  const Vector3d s = V.head<3>() + w.cross(r) - u * Rd;
  const Matrix3x ds = dV.topRows<3>() + cross_d(w, dw, r, dr) - Rd * du;
  const Vector3d al = Acc.head<3>(), alw = Acc.tail<3>();
  const Vector3d acc = al + alw.cross(r) + w.cross(rdot) - udot * Rd;
  const Matrix3x dacc =
      dAcc.topRows<3>() + cross_d(alw, dAcc.bottomRows<3>(), r, dr) + cross_d(w, dw, rdot, drdot) - Rd * dudot;
  const Vector3d E[3] = {t1, g.t2, n};
  const Vector3d Ed[3] = {t1d, t2d, ndot};
  const Matrix3x* dEd[3] = {&dt1d, &dt2d, &dndot};
  Matrix3x rows(3, nv);
  for (int i = 0; i < 3; ++i)
    rows.row(i) = Ed[i].transpose() * ds + s.transpose() * (*dEd[i]) + E[i].transpose() * dacc +
                  acc.transpose() * gd.E(i);
  drift_out.noalias() = D.lazyProduct(rows);
  // Adot = Wdot Aw + W Awdot, Awdot = dJ_c - [rdot]x Jw - [r]x dJ_w (- udot at the radius column); the same sums,
  // the products written in place (no temporaries)
  Matrix3x Awdot = dJ.topRows<3>();
  Awdot.noalias() -= skew3(rdot) * jac.bottomRows<3>();
  Awdot.noalias() -= skew3(r) * dJ.bottomRows<3>();
  if (radius_col >= 0) Awdot.col(radius_col) -= udot;
  Matrix3d ET, EdT;
  for (int i = 0; i < 3; ++i) {
    ET.row(i) = E[i].transpose();
    EdT.row(i) = Ed[i].transpose();
  }
  Matrix3x Wd(3, nv);
  Wd.noalias() = EdT.lazyProduct(Aw);
  Wd.noalias() += ET.lazyProduct(Awdot);
  adot_out.noalias() = D.lazyProduct(Wd);
}

// d(A_w^T mu_w)/dq at fixed mu_w (the wheel's constraint force's generalized force, differentiated), added into T
// (n x n). A_w = D E A_c with E's rows (t1, t2, n) and A_c = J_c - [r]x J_w - u e_R the contact point's Jacobian
// (p = c + r, r = -R u), so A_w^T mu_w = J_O^T (f, p x f) - e_R^T (u . f) with f = E^T D^T mu_w (world force at p)
// and J_O the frame's joint's world Jacobian at the origin. Its derivative:
//   (dJ_O^T at fixed (f, p x f))  [force_jacobian_dq]  + A_c^T df - J_w^T [f]x dp - e_R^T (f^T du),
// df = sum_i (D^T mu_w)_i dE_i, dp = J_c + dr (the geometry's dq, gd: on the wheel's columns `cols`, like Jc, the
// frame's gathered LOCAL_WORLD_ALIGNED Jacobian, and Awc, the gathered A_c; radius_col: the radius column among
// them or -1). The twin's check: mu^T d(A S_l)/dq = S_l^T T row by row (tests/test_compiled_derivatives*.py hold the
// compiled derivatives to the Python path's, which sums mu_r d(A S_l)/dq over the columns of S).
template <class G, class JM>
void wheel_force_dq(const pin::Model& model, const JM& Jworld, pin::JointIndex jid, const G& g,
                    const WheelGeometryDq& gd, const Eigen::Ref<const MatrixXd>& D, const Eigen::Ref<const VectorXd>& mu,
                    const Matrix6x& Jc, const MatrixXd& Awc, const std::vector<int>& cols, int radius_col,
                    MatrixXd& block, MatrixXd& T) {
  const Vector3d lam = D.transpose() * mu;
  const Vector3d f = lam[0] * g.t1 + lam[1] * g.t2 + lam[2] * g.n;
  Vector6d phi;
  phi << f, g.p.cross(f);
  force_jacobian_dq(model, Jworld, jid, phi, 1.0, T);
  Matrix3x df = lam[0] * gd.t1;
  df.noalias() += lam[1] * gd.t2;
  df.noalias() += lam[2] * gd.n;
  Matrix3x dp = Jc.topRows<3>() + gd.r;
  Matrix3x fdp(3, dp.cols());
  fdp.noalias() = skew3(f) * dp;
  block.noalias() = Awc.transpose().lazyProduct(df);  // (3-deep: coefficient-wise)
  block.noalias() -= Jc.bottomRows<3>().transpose().lazyProduct(fdp);
  if (radius_col >= 0) block.row(radius_col) -= f.transpose() * gd.u;
  for (size_t a = 0; a < cols.size(); ++a)
    for (size_t b = 0; b < cols.size(); ++b) T(cols[a], cols[b]) += block(a, b);
}

}  // namespace derivs
}  // namespace robotdyn
