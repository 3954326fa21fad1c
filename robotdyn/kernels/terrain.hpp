// robotdyn/kernels/terrain.hpp: terrains z = f(x, y) with gradient and Hessian, twin of
// robotdyn/constraints/terrain.py (RampTerrain: plane, SineTerrain, BumpTerrain), as the rolling wheels use them.
//
//   0 plane   f = h + gx x + gy y                        c = (h, gx, gy)
//   1 sine    f = a sin(kx x + ky y + phase)             c = (a, kx, ky, phase)
//   2 bump    f = h/2 (1 + tanh((x - x0)/w)), minus the same step at x0 + length when length is not NaN (a plateau)
//                                                          c = (h, x0, w, length)
// normal n = (-f_x, -f_y, 1) / |(-f_x, -f_y, 1)| (Terrain.normal).
#pragma once

#include "common.hpp"

#include <cmath>

namespace robotdyn {
namespace kernels {

struct Terrain {
  int kind = 0;
  double c[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
  bool flat() const { return kind == 0; }
  void step(double x, double x0, double& f, double& fx, double& fxx) const {
    const double h = c[0], w = c[2];
    const double t = std::tanh((x - x0) / w), s = 1.0 - t * t;
    f = 0.5 * h * (1 + t);
    fx = 0.5 * h * s / w;
    fxx = -h * t * s / (w * w);
  }
  // height, gradient and Hessian at (x, y)
  void eval(double x, double y, double& f, Eigen::Vector2d& g, Eigen::Matrix2d& H) const {
    if (kind == 0) {
      f = c[0] + c[1] * x + c[2] * y;
      g << c[1], c[2];
      H.setZero();
    } else if (kind == 1) {
      const double arg = c[1] * x + c[2] * y + c[3];
      f = c[0] * std::sin(arg);
      const double co = c[0] * std::cos(arg);
      g << co * c[1], co * c[2];
      const double si = -c[0] * std::sin(arg);
      H << si * c[1] * c[1], si * c[1] * c[2], si * c[2] * c[1], si * c[2] * c[2];
    } else {
      double fx, fxx;
      step(x, c[1], f, fx, fxx);
      if (!std::isnan(c[3])) {
        double f2, fx2, fxx2;
        step(x, c[1] + c[3], f2, fx2, fxx2);
        f -= f2;
        fx -= fx2;
        fxx -= fxx2;
      }
      g << fx, 0.0;
      H << fxx, 0.0, 0.0, 0.0;
    }
  }
  Vector3d normal(double x, double y) const {
    double f;
    Eigen::Vector2d g;
    Eigen::Matrix2d H;
    eval(x, y, f, g, H);
    Vector3d m(-g[0], -g[1], 1.0);
    return m / m.norm();
  }
};

}  // namespace kernels
}  // namespace robotdyn
