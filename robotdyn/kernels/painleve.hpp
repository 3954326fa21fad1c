// robotdyn/kernels/painleve.hpp: the Painleve check of sliding wheels, twin of robotdyn/contact/painleve.py (the same
// steps in the same order; its docstring derives them). With the friction of the sliding wheels fixed by their
// slip, the separation accelerations of their contacts depend on their loads N as a_n = a_n0 + D N; the contact
// problem has one solution for every a_n0 iff D is a P-matrix (all principal minors positive), otherwise none or
// two (Painleve). From the slipping wheels' system K x = b already factorised (sliding.hpp, x = (nudot, lambda_R)):
//
//   D^-1 = -[K^-1 M Z]_(the sliding wheels' loads),   Z = A_R^T (A_R A_R^T)^-1 E,
//
// E selecting the sliding wheels' normal rows among the rows A_R. A positive definite symmetric part of D settles
// it; otherwise D's principal minors are tried by size, then by bit mask (a minor on wheels J: the others' loads
// at zero). For a single wheel j the threshold is mu_P = mu_j D0_jj / F_jj, F = -D [K^-1 U]_(loads) the friction's
// part of D (U the columns J_t,i^T c_i), D0 = D + F, where its law is proportional to mu (Coulomb; a linear tyre
// once saturated).
#pragma once

#include "common.hpp"

#include <cmath>
#include <vector>

namespace robotdyn {
namespace kernels {

// The check's buffers (a member of SlipSystem, so that regular states allocate nothing once sized).
struct PainleveCheck {
  MatrixXd AR, gram, sel, Yg, Z, MZ, Y, E, D, Q, sub;
  Eigen::LLT<MatrixXd> llt;
  Eigen::PartialPivLU<MatrixXd> gram_lu;

  // The first principal minor of D that is not positive, as a bit mask (bit i: wheel i), or 0 (D is a P-matrix).
  int first_violation() {
    const int w = static_cast<int>(D.rows());
    llt.compute(0.5 * (D + D.transpose()));
    if (llt.info() == Eigen::Success) return 0;
    for (int size = 1; size <= w; ++size) {
      for (int mask = 1; mask < (1 << w); ++mask) {
        int count = 0;
        for (int i = 0; i < w; ++i) count += (mask >> i) & 1;
        if (count != size) continue;
        std::vector<int> idx;
        for (int i = 0; i < w; ++i)
          if ((mask >> i) & 1) idx.push_back(i);
        sub.resize(size, size);
        for (int a = 0; a < size; ++a)
          for (int b = 0; b < size; ++b) sub(a, b) = D(idx[a], idx[b]);
        if (!(sub.determinant() > 0.0)) return mask;  // NaN too
      }
    }
    return 0;
  }
};

}  // namespace kernels
}  // namespace robotdyn
