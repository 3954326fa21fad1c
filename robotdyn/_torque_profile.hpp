// Motor torques as data, evaluated without Python: the C++ side of robotdyn/torque_profile.py.
//
// A profile is a sum of terms, each a vector over the motors times a scalar function of time:
//   0 constant      tau += c
//   1 sine          tau += c sin(omega t + phase)    for start <= t <= stop
//   2 table         tau += piecewise-linear interpolation of values at times (held outside them)
//   3 polynomial    tau += c_0 + t (c_1 + t (c_2 + ...))   for start <= t <= stop (Horner, rows of coef)
//   4 piecewise     tau += c_j0 + s (c_j1 + s (c_j2 + ...)), s = t - x_j, on the piece x_j <= t <= x_j+1 of knots
//                   x_0 < ... < x_m (par[1:]; par[0] a flag the Python side reads), zero outside [x_0, x_m]; coef
//                   rows j (d + 1) ... j (d + 1) + d hold piece j's coefficients, lowest power first
// with the same floating-point operations in the same order as TorqueProfile.__call__ (libm's sin on both sides),
// so that the compiled and the scipy paths see the same torques bit for bit.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace robotdyn {

struct TorqueTerm {
  int kind;
  Eigen::MatrixXd coef;  // (1, motors) or (points, motors)
  std::vector<double> par;
};

class TorqueProfile {
 public:
  TorqueProfile() = default;
  TorqueProfile(int motors, const std::vector<int>& kinds, const std::vector<Eigen::MatrixXd>& coefs,
                const std::vector<std::vector<double>>& pars)
      : motors_(motors) {
    if (kinds.size() != coefs.size() || kinds.size() != pars.size())
      throw std::invalid_argument("torque profile: kinds, coefficients and parameters differ in length");
    for (size_t i = 0; i < kinds.size(); ++i) {
      TorqueTerm term{kinds[i], coefs[i], pars[i]};
      if (term.coef.cols() != motors && !(term.coef.rows() == motors && term.coef.cols() == 1))
        throw std::invalid_argument("torque profile: a term for another number of motors");
      if (term.coef.cols() == 1 && motors != 1) term.coef.transposeInPlace();  // a vector given as a column
      if (term.kind == 1 && term.par.size() != 4) throw std::invalid_argument("sine term: 4 parameters expected");
      if (term.kind == 2 && (term.par.empty() || static_cast<Eigen::Index>(term.par.size()) != term.coef.rows()))
        throw std::invalid_argument("table term: one time per row of values expected");
      if (term.kind == 3 && term.par.size() != 2) throw std::invalid_argument("polynomial term: 2 parameters expected");
      if (term.kind == 4 && (term.par.size() < 3 || term.coef.rows() % (term.par.size() - 2) != 0))
        throw std::invalid_argument("piecewise polynomial term: the same number of coefficients for every piece expected");
      if (term.kind < 0 || term.kind > 4) throw std::invalid_argument("unknown torque term");
      terms_.push_back(std::move(term));
    }
  }

  int motors() const { return motors_; }

  // tau(t) into out (motors)
  void eval(double t, Eigen::Ref<Eigen::VectorXd> out) const {
    out.setZero();
    for (const TorqueTerm& term : terms_) {
      if (term.kind == 0) {
        out += term.coef.row(0).transpose();
      } else if (term.kind == 1) {
        if (term.par[2] <= t && t <= term.par[3]) {
          const double s = std::sin(term.par[0] * t + term.par[1]);
          for (int j = 0; j < motors_; ++j) out[j] += term.coef(0, j) * s;
        }
      } else if (term.kind == 3) {
        if (term.par[0] <= t && t <= term.par[1]) {
          const Eigen::Index last = term.coef.rows() - 1;
          for (int j = 0; j < motors_; ++j) {
            double p = term.coef(last, j);
            for (Eigen::Index i = last - 1; i >= 0; --i) p = term.coef(i, j) + t * p;
            out[j] += p;
          }
        }
      } else if (term.kind == 4) {
        const std::vector<double>& x = term.par;  // x[0]: the flag; knots x[1] ... x[m + 1]
        if (x[1] <= t && t <= x.back()) {
          const Eigen::Index pieces = static_cast<Eigen::Index>(x.size()) - 2;
          const Eigen::Index rows = term.coef.rows() / pieces;
          Eigen::Index j = static_cast<Eigen::Index>(std::upper_bound(x.begin() + 1, x.end(), t) - x.begin()) - 2;
          j = std::min(std::max<Eigen::Index>(j, 0), pieces - 1);
          const double s = t - x[j + 1];
          const Eigen::Index first = j * rows, last = first + rows - 1;
          for (int c = 0; c < motors_; ++c) {
            double p = term.coef(last, c);
            for (Eigen::Index i = last - 1; i >= first; --i) p = term.coef(i, c) + s * p;
            out[c] += p;
          }
        }
      } else {
        const std::vector<double>& ts = term.par;
        if (t <= ts.front()) {
          out += term.coef.row(0).transpose();
        } else if (t >= ts.back()) {
          out += term.coef.row(term.coef.rows() - 1).transpose();
        } else {
          const size_t i = static_cast<size_t>(std::upper_bound(ts.begin(), ts.end(), t) - ts.begin()) - 1;
          const double s = (t - ts[i]) / (ts[i + 1] - ts[i]);
          for (int j = 0; j < motors_; ++j)
            out[j] += term.coef(i, j) + s * (term.coef(i + 1, j) - term.coef(i, j));
        }
      }
    }
  }

 private:
  int motors_ = 0;
  std::vector<TorqueTerm> terms_;
};

}  // namespace robotdyn
