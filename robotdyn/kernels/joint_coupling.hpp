// robotdyn/kernels/joint_coupling.hpp: a holonomic coupling q_i = f(q_j) of two one-dof joints with a cosine law,
// twin of robotdyn/constraints/joint_coupling.py (JointCoupling with a CosineLaw):
//
//   f(q_j) = amplitude cos(rate q_j + phase) + offset
//   residual  phi = q_i - f(q_j);  row  A = e_i^T - f'(q_j) e_j^T;  drift  Adot v = -f''(q_j) v_j^2
#pragma once

#include "common.hpp"

#include <cmath>

namespace robotdyn {
namespace kernels {

struct Coupling {  // q[i] = amplitude cos(rate q[j] + phase) + offset
  int i, j;
  double amplitude, rate, phase, offset;
};

// The coupling's row into A (zeroed beforehand) and its residual at `row` (JointCoupling.jacobian). Returns the
// next row.
inline int coupling_rows(const Coupling& c, const VectorXd& q, int row, MatrixXd& A, VectorXd& residual) {
  const double arg = c.rate * q[c.j] + c.phase;
  A(row, c.i) = 1.0;
  A(row, c.j) -= -c.amplitude * c.rate * std::sin(arg);
  residual[row] = q[c.i] - (c.amplitude * std::cos(arg) + c.offset);
  return row + 1;
}

// The coupling's drift -f''(q_j) v_j^2 at `row` (JointCoupling.drift). Returns the next row.
inline int coupling_drift(const Coupling& c, const VectorXd& q, const VectorXd& v, int row, VectorXd& drift) {
  const double arg = c.rate * q[c.j] + c.phase;
  const double vr = v[c.j];
  drift[row] = -(-c.amplitude * c.rate * c.rate * std::cos(arg)) * vr * vr;
  return row + 1;
}

}  // namespace kernels
}  // namespace robotdyn
