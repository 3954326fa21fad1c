// robotdyn/kernels/compliant_rolling.hpp: compliant wheels that roll while in contact, twin of
// robotdyn/contact/compliant_rolling.py (forward, pressing; the switching run is robotdyn/simulation/
// compiled_rolling.py on the compiled path, robotdyn/simulation/compliant_rolling.py on the Python one).
//
// A compliant wheel with friction = "rolling" has its normal force law (kernels/compliant_contact.hpp) and, while
// that force is > 0, its tangential rows G_i = D_i (t1, t2)^T A_w (the rigid wheel's rows of kernels/
// rolling_contact.hpp with the wheel's directions D_i, no normal row) as constraints of the motion. With the
// contact set C given (the run's mode, data of the compiled run), G = the rows of the wheels in C, G_r = G S and
// f = B_r tau - h_r + S^T Q:
//   M_r nudot = f + G_r^T lambda,   G_r nudot = target = -(G w + Gdot v) - beta G_r nu
// solved as the Python path does: W = G_r M_r^-1 G_r^T (symmetrised), its eigenvectors with eigenvalues above
// RCOND times the largest (redundant rows: minimum-norm lambda), lambda = V_k diag(1 / l_k) V_k^T (target -
// G_r M_r^-1 f), nudot = M_r^-1 (f + G_r^T lambda).
// The contact indicator of a wheel (NormalLaw.pressing: > 0 exactly where the law pushes):
//   linear         min(delta, delta + c / k deltadot)
//   Hunt-Crossley  min(delta, delta (1 + lambda / k deltadot))
#pragma once

#include "common.hpp"
#include "compliant_contact.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <limits>

namespace robotdyn {
namespace kernels {

// Relative eigenvalue cut of G_r M_r^-1 G_r^T below which rows count as redundant (compliant_rolling.RCOND).
constexpr double ROLLING_RCOND = 1e-10;

// The contact indicator [m] of a normal law at penetration delta [m] and its rate [m/s] (NormalLaw.pressing).
inline double pressing(const NormalLaw& law, double delta, double rate) {
  if (law.kind == 0) return std::min(delta, delta + law.c / law.k * rate);
  return std::min(delta, delta * (1.0 + law.c / law.k * rate));
}

// nudot (in place of f) and lambda of the rolling rows G_r (m, k) with the acceleration target (m,), M_r factored
// in llt (compliant_rolling.forward). Returns false if the result is not finite.
template <class LLT>
inline bool rolling_accelerations(const LLT& llt, const MatrixXd& Gr, const VectorXd& target, VectorXd& f,
                                  VectorXd& lambda, MatrixXd& MinvGT) {
  const int m = static_cast<int>(Gr.rows());
  llt.solveInPlace(f);  // M_r^-1 f
  MinvGT = Gr.transpose();
  llt.solveInPlace(MinvGT);
  MatrixXd W = Gr * MinvGT;
  W = 0.5 * (W + W.transpose()).eval();
  Eigen::SelfAdjointEigenSolver<MatrixXd> eig(W);
  const VectorXd& vals = eig.eigenvalues();
  const double top = std::max(m ? vals.maxCoeff() : 0.0, std::numeric_limits<double>::min());
  const VectorXd r = eig.eigenvectors().transpose() * (target - Gr * f);
  VectorXd c = VectorXd::Zero(m);
  for (int i = 0; i < m; ++i)
    if (vals[i] > ROLLING_RCOND * top) c[i] = r[i] / vals[i];
  lambda.noalias() = eig.eigenvectors() * c;
  f.noalias() += MinvGT * lambda;
  return f.allFinite() && lambda.allFinite();
}

}  // namespace kernels
}  // namespace robotdyn
