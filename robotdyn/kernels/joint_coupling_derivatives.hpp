// robotdyn/kernels/joint_coupling_derivatives.hpp: configuration derivatives of a joint coupling's row
// q_i = f(q_j), f = amplitude cos(rate q_j + phase) + offset (a CosineLaw, the only law the evaluator compiles), twin
// of robotdyn/constraints/row_derivatives.py (coupling_velocity_dq, _third, drift_dq) beside joint_coupling.hpp
// (robotdyn/constraints/joint_coupling.py): d(A x)/dq = -f''(q_j) x_j e_j^T, dgamma/dq = -f'''(q_j) v_j^2 e_j^T and
// Adot = -f''(q_j) v_j e_j^T.
#pragma once

#include <cmath>

namespace robotdyn {
namespace derivs {

struct CosineCoupling {
  int i, j;
  double amplitude, rate, phase;
  double second(double qj) const { return -amplitude * rate * rate * std::cos(rate * qj + phase); }  // f''
  double third(double qj) const { return amplitude * rate * rate * rate * std::sin(rate * qj + phase); }  // f'''
};

// one row (1 x n) each: out.row(0) zero except the reference coordinate's column
template <class Out>
void coupling_velocity_dq(const CosineCoupling& c, double qj, double xj, Out&& out) {
  out.setZero();
  out(0, c.j) = -c.second(qj) * xj;
}

template <class Out1, class Out2>
void coupling_drift_dq(const CosineCoupling& c, double qj, double vj, Out1&& drift_out, Out2&& adot_out) {
  drift_out.setZero();
  drift_out(0, c.j) = -c.third(qj) * vj * vj;
  adot_out.setZero();
  adot_out(0, c.j) = -c.second(qj) * vj;
}

// d(A^T mu)/dq at fixed mu of the row (A^T mu = mu (e_i - f'(q_j) e_j)): -f''(q_j) mu at (j, j), added into T
template <class Out>
void coupling_force_dq(const CosineCoupling& c, double qj, double mu, Out&& T) {
  T(c.j, c.j) += -c.second(qj) * mu;
}

}  // namespace derivs
}  // namespace robotdyn
